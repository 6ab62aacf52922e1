// [simulation]: the forced response's duration, output and trajectory steps, CVODES
// settings, which solutions and the figures' names.
#include <algorithm>
#include <cmath>
#include <limits>

#include "io/design_sections.hpp"

namespace freeflex::io_detail {

void read_simulation(Section& root, Design& d, Outputs& outputs) {
  Section s = root.table("simulation");
  if (!s.present()) return;
  SimulationStudy st;
  SimulationOptions& o = st.options;
  auto dur = s.number("duration_s", kTime, true);
  if (dur) o.duration_s = *dur;
  // without output_step_s, 600 rows over the duration (a design-file rule, not a library default)
  auto step = s.number("output_step_s", Range::positive(), false);
  o.output_step_s = step.value_or(o.duration_s / 600.0);
  if (dur && step && *step <= *dur)  // a step beyond the duration: the library's check, below
    check_count(s, "output_step_s", s.key_path("output_step_s") + " = " + shortest(*step),
                "duration_s = " + shortest(*dur), *dur, *step, "output rows", lim::kMaxOutputRows,
                "raise output_step_s or shorten duration_s");
  auto traj = s.number("trajectory_step_s", Range::positive(), false);
  o.trajectory_step_s = traj.value_or(o.trajectory_step_s);
  o.integrator.rtol = s.number("rtol", Range{0.0, 1.0, true, true}, false).value_or(o.integrator.rtol);
  // an absolute error of 1 (m, rad, modal amplitude) or more would switch the error control off
  o.integrator.atol = s.number("atol", Range{0.0, 1.0, true, true}, false).value_or(o.integrator.atol);
  o.integrator.max_step = s.number("max_step_s", Range::nonnegative(), false).value_or(o.integrator.max_step);
  o.integrator.method = s.enumerated<IntegratorOptions::Method>("method", false).value_or(o.integrator.method);
  o.full_variables =
      s.enumerated<SimulationOptions::Variables>("full_model_variables", false).value_or(o.full_variables);
  o.first_order_variables =
      s.enumerated<SimulationOptions::Variables>("first_order_variables", false).value_or(o.first_order_variables);
  o.first_order_solver = s.enumerated<SimulationOptions::FirstOrderSolver>("first_order_solver", false)
                             .value_or(o.first_order_solver);
  if (o.first_order_solver == SimulationOptions::FirstOrderSolver::Taylor && o.integrator.rtol < 1e-10)
    s.problem("rtol", s.key_path("rtol") + " = " + shortest(o.integrator.rtol) +
                          " with first_order_solver = \"taylor\": expected >= 1e-10 (it takes the nominal motion's "
                          "coefficients to 1e-11 of their size, the sampled motion's own accuracy, so a tighter rtol "
                          "would not be met and its error estimate would not show it; docs/theory.md section 8)");
  if (o.first_order_solver == SimulationOptions::FirstOrderSolver::Taylor && root.has("motion"))
    s.problem("first_order_solver", s.key_path("first_order_solver") +
                                        " = \"taylor\" integrates the perturbation solution about a free or optimized "
                                        "motion; a prescribed [motion] is integrated by the `method` integrator: "
                                        "remove the key or set it to \"integrator\"");
  if (root.has("motion") && s.has("full_model_variables") && o.full_variables != SimulationOptions::Variables::Physical)
    s.problem("full_model_variables", s.key_path("full_model_variables") + " = \"" + to_string(o.full_variables) +
                                          "\": with a prescribed [motion] the full model integrates q alone, in physical "
                                          "coordinates; remove the key or set it to \"physical\"");
  st.nonlinear = s.boolean("nonlinear", false).value_or(st.nonlinear);
  st.perturbation = s.boolean("perturbation", false).value_or(st.perturbation);
  st.error_estimate = s.boolean("error_estimate", false).value_or(st.error_estimate);
  st.compare_stiffening = s.boolean("compare_stiffening", false).value_or(st.compare_stiffening);
  if (dur) report_field_problems(s, problems(o), {{"duration_s", "duration_s"},
                                                  {"first_order_variables", "first_order_variables"},
                                                  {"output_step_s", "output_step_s"},
                                                  {"trajectory_step_s", "trajectory_step_s"},
                                                  {"integrator.rtol", "rtol"},
                                                  {"integrator.atol", "atol"},
                                                  {"integrator.max_step", "max_step_s"}});
  // the perturbation solution samples the zero-order motion at the finer of the two steps
  // (the output rows are bounded above)
  const double samples_step = trajectory_step(o);
  if (st.perturbation && !root.has("maneuver") && dur && (step || !s.has("output_step_s")) &&
      (traj || !s.has("trajectory_step_s")) && samples_step < o.output_step_s)
    check_count(s, traj ? "trajectory_step_s" : "duration_s",
                traj ? s.key_path("trajectory_step_s") + " = " + shortest(o.trajectory_step_s)
                     : s.key_path("duration_s") + " = " + shortest(*dur),
                traj ? "duration_s = " + shortest(*dur)
                     : "trajectory_step_s = " + shortest(samples_step) + " (the default)",
                *dur, samples_step, "samples of the zero-order motion", lim::kMaxTrajectorySamples,
                "raise trajectory_step_s or shorten duration_s");
  if (!st.nonlinear && !st.perturbation)
    s.problem("nonlinear", s.key_path("nonlinear") + " and perturbation are both false: nothing to simulate");
  if (auto name = s.string("rigid_figure", false, true)) st.rigid_figure = *name;
  if (auto name = s.string("elastic_figure", false, true)) st.elastic_figure = *name;
  if (auto name = s.string("tip_figure", false, true)) st.tip_figure = *name;
  if (st.compare_stiffening && !st.nonlinear)
    s.problem("compare_stiffening", s.key_path("compare_stiffening") + " = true needs nonlinear = true (it reruns the full model)");
  s.finish();
  outputs.named(s, "rigid_figure", st.rigid_figure, {".gp", ".png"});
  outputs.named(s, "elastic_figure", st.elastic_figure, {".gp", ".png"});
  if (st.nonlinear) outputs.fixed("[simulation]", "nonlinear.csv");
  if (st.perturbation) outputs.fixed("[simulation]", "perturbation.csv");
  if (st.compare_stiffening) {
    outputs.fixed("[simulation]", d.geometric_stiffening ? "nonlinear_stiffening_off.csv" : "nonlinear_stiffening_on.csv");
    outputs.named(s, "tip_figure", st.tip_figure, {".gp", ".png"});
  }
  for (const char* f : {"vibration.gp", "vibration.png"})
    outputs.fixed("[simulation]", f);
  // a [[load]] that has problems of its own is not missing as well
  if (!root.has("load") && !root.has("maneuver") && !root.has("motion"))
    s.problem("duration_s", "[simulation] needs at least one [[load]], a [maneuver] or a [motion] to respond to");
  if (dur && !d.loads.empty() && !root.has("maneuver") && !root.has("motion")) {
    double first = std::numeric_limits<double>::infinity();
    for (const auto& l : d.loads) first = std::min(first, l.profile.times().front());
    if (first >= *dur)
      s.problem("duration_s", s.key_path("duration_s") + " = " + shortest(*dur) +
                                  " ends before any load acts (the first at " + shortest(first) +
                                  " s): nothing would move");
  }
  d.simulation = st;
}

}  // namespace freeflex::io_detail
