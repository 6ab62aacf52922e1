// [controller]: the TV-LQR's actuators, horizon, weights and gain grid, and the runs that
// compare it with the open loop.
#include <algorithm>
#include <cmath>
#include <limits>

#include "io/design_sections.hpp"

namespace freeflex::io_detail {

void read_controller(Section& root, Design& d, Outputs& outputs, const std::vector<std::string>& rejected) {
  Section c = root.table("controller");
  if (!c.present()) return;
  ControllerStudy st;
  c.choice("type", {"tvlqr"}, false);  // the only controller so far
  bool names_ok = false;  // else the per-actuator sizes below are not checked
  if (auto names = c.string_array("actuators", true)) {
    st.actuators = actuator_indices(c, "actuators", *names, d, rejected);
    names_ok = st.actuators.size() == names->size();
    if (names_ok) st.actuator_names = *names;
  }
  const std::size_t m = st.actuators.size();
  st.limits.resize(static_cast<Eigen::Index>(m));
  for (std::size_t k = 0; k < m; ++k) {
    const double lim = d.actuators[st.actuators[k] - d.loads.size()].limit;
    st.limits(static_cast<Eigen::Index>(k)) = lim > 0 ? lim : std::numeric_limits<double>::infinity();
  }
  auto horizon = c.number("horizon_s", kTime, true);
  st.horizon_s = horizon.value_or(st.horizon_s);
  auto state_weight = [&](const char* key, double fallback) {
    const double w = c.number(key, Range().supported(-lim::kMaxWeight, lim::kMaxWeight), false).value_or(fallback);
    if (w < 0.0) {
      c.problem(key, c.key_path(key) + " = " + shortest(w) +
                         ", must be >= 0 (the state weight Q must be positive semidefinite)");
      return 0.0;
    }
    return w;
  };
  st.weight_elastic = state_weight("weight_elastic", st.weight_elastic);
  st.weight_rigid_position = state_weight("weight_rigid_position", st.weight_rigid_position);
  st.weight_rigid_rate = state_weight("weight_rigid_rate", st.weight_rigid_rate);
  st.input_weights = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(m));
  if (c.has("input_weights")) {
    auto w = c.number_array("input_weights", Range().supported(-lim::kMaxWeight, lim::kMaxWeight), false);
    if (w) {  // else reported by number_array, which returns no empty array
      const auto [lo, hi] = std::minmax_element(w->begin(), w->end());
      if (!(*lo > 0.0)) {
        c.problem("input_weights", c.key_path("input_weights") +
                                       ": every entry must be > 0 (the input weight R must be positive definite)");
      } else if (*lo < lim::kMinInputWeight) {
        c.problem("input_weights", c.key_path("input_weights") + ": every entry must be in [" +
                                       shortest(lim::kMinInputWeight) + ", " + shortest(lim::kMaxWeight) + "]");
      } else if (*hi > lim::kMaxInputWeightSpread * *lo) {
        c.problem("input_weights", c.key_path("input_weights") + " spans " + shortest(*lo) + " to " + shortest(*hi) +
                                       ", more than a factor " + shortest(lim::kMaxInputWeightSpread) +
                                       " (R would be numerically singular); rescale the actuators' commands instead");
      } else if (w->size() != m) {
        if (names_ok)
          c.problem("input_weights",
                    c.key_path("input_weights") + " needs one entry per actuator (" + std::to_string(m) + ")");
      } else {
        st.input_weights = Eigen::Map<const Eigen::VectorXd>(w->data(), static_cast<Eigen::Index>(m));
      }
    }
  }
  if (st.weight_elastic + st.weight_rigid_position + st.weight_rigid_rate <= 0.0)
    c.problem("weight_elastic", "controller: every state weight is zero; Q must weight something");
  auto grid = c.number("grid_step_s", Range::positive(), false);
  st.grid_step_s = grid.value_or(st.grid_step_s);
  if (horizon && (grid || !c.has("grid_step_s"))) {
    const std::string key = grid ? "grid_step_s" : "horizon_s";
    const std::string lead = grid ? c.key_path("grid_step_s") + " = " + shortest(*grid)
                                  : c.key_path("horizon_s") + " = " + shortest(*horizon);
    const std::string other =
        grid ? "horizon_s = " + shortest(*horizon) : "grid_step_s = " + shortest(st.grid_step_s) + " (the default)";
    // the gains stored: grid points x actuators x the first-order state, 2 (3 + noa)
    const double per_point = static_cast<double>(m) * 2.0 * (3 + d.noa);
    if (check_count(c, key, lead, other, *horizon, st.grid_step_s, "TV-LQR gain grid points", lim::kMaxOutputRows,
                    "raise grid_step_s or shorten horizon_s") &&
        m > 0)
      check_count(c, key, lead + " and " + std::to_string(m) + " actuator(s) at noa = " + std::to_string(d.noa), other,
                  *horizon, st.grid_step_s, "TV-LQR gain grid points of " + shortest(per_point) + " doubles each",
                  std::floor(lim::kMaxGainStorage / per_point),
                  "raise grid_step_s, shorten horizon_s or use fewer actuators (the gains are kept in memory)");
  }
  auto until = c.number("simulate_until_s", kTime, false);
  st.simulate_until_s = until.value_or(st.horizon_s);
  if (auto name = c.string("figure", false, true)) st.figure = *name;
  const Range tolerance = Range::positive().supported(1e-16, 1.0);
  st.closed_loop_rtol = c.number("closed_loop_rtol", tolerance, false).value_or(st.closed_loop_rtol);
  st.closed_loop_atol = c.number("closed_loop_atol", tolerance, false).value_or(st.closed_loop_atol);
  st.closed_loop_first_order_method = c.enumerated<ClosedLoopMethod>("closed_loop_first_order_method", false)
                                          .value_or(st.closed_loop_first_order_method);
  st.tvlqr_method = c.enumerated<TvlqrOptions::Method>("tvlqr_method", false).value_or(st.tvlqr_method);
  auto gauss_steps = c.integer("closed_loop_gauss_steps", 1, 1000, false);
  st.closed_loop_gauss_steps = static_cast<int>(gauss_steps.value_or(st.closed_loop_gauss_steps));
  st.error_estimate = c.boolean("error_estimate", false).value_or(st.error_estimate);
  c.finish();
  outputs.named(c, "figure", st.figure, {".gp", ".png"});
  outputs.named(c, "figure", st.figure + "_commands", {".gp", ".png"});
  outputs.fixed("[controller]", "comparison.csv");
  // a vibration-aware maneuver's cases carry its name and its rigid optimum's
  std::vector<std::string> prefixes{""};
  if (d.maneuver && d.maneuver->problem.elastic) prefixes = {"vibration_aware_", "rigid_optimum_"};
  for (const std::string& prefix : prefixes)
    for (const char* cs : {"open_loop", "tvlqr"})
      for (const char* model : {"first_order", "nonlinear"}) {
        outputs.fixed("[controller]", "commands_" + prefix + cs + "_" + model + ".csv");
        outputs.fixed("[controller]", "case_" + prefix + cs + "_" + model + ".csv");
      }
  if (!root.has("load") && !root.has("maneuver"))
    c.problem("actuators",
              "[controller] needs a nominal motion whose vibration it suppresses: add a [[load]] or a "
              "[maneuver]");
  if (d.maneuver && horizon) {
    const ManeuverProblem& p = d.maneuver->problem;
    const double shortest_maneuver = p.free_time ? p.t_min_s : p.duration_s;
    if (st.horizon_s < shortest_maneuver)
      c.problem("horizon_s", c.key_path("horizon_s") + " = " + shortest(st.horizon_s) + ", shorter than the maneuver (" +
                                 (p.free_time ? "maneuver.duration_min_s = " : "maneuver.duration_s = ") +
                                 shortest(shortest_maneuver) + ")");
  }
  if (!d.loads.empty() && !d.maneuver) {
    const double end = loads_end(d);
    if (horizon && st.horizon_s < end)
      c.problem("horizon_s", c.key_path("horizon_s") + " = " + shortest(st.horizon_s) +
                                 ", shorter than the maneuver (its loads act until " + shortest(end) + " s)");
  }
  // The comparison runs: from 0 to simulate_until_s, at the [simulation] output and
  // trajectory steps (or 0.005 s and the default 0.001 s without one).
  const bool have_end = until || (!c.has("simulate_until_s") && horizon);
  if (have_end) {
    const std::string end_key = until ? "simulate_until_s" : "horizon_s";
    const std::string end_text = until ? c.key_path("simulate_until_s") : "controller.simulate_until_s (= horizon_s)";
    const double t_end = st.simulate_until_s;
    const bool from_simulation = d.simulation.has_value();
    const double out_step = from_simulation ? d.simulation->options.output_step_s : 0.005;
    const double traj_step = trajectory_step(from_simulation ? d.simulation->options : SimulationOptions{});
    const std::string out_text =
        from_simulation ? "simulation.output_step_s" : "the fixed output step (no [simulation])";
    if (until && horizon && !d.maneuver && t_end < st.horizon_s)
      c.problem("simulate_until_s", c.key_path("simulate_until_s") + " = " + shortest(t_end) +
                                        " is shorter than horizon_s = " + shortest(st.horizon_s) +
                                        " (without a [maneuver] the nominal motion is "
                                        "computed up to simulate_until_s, and the TV-LQR needs it over the horizon)");
    else if (out_step > t_end)
      c.problem(end_key, end_text + " = " + shortest(t_end) + " is shorter than " + out_text + " = " +
                             shortest(out_step) + "; it must not be");
    else if (check_count(c, end_key, end_text + " = " + shortest(t_end), out_text + " = " + shortest(out_step), t_end,
                         out_step, "output rows of the comparison runs", lim::kMaxOutputRows,
                         from_simulation ? "shorten simulate_until_s or raise simulation.output_step_s"
                                         : "shorten simulate_until_s") &&
             traj_step < out_step)
      check_count(
          c, end_key, end_text + " = " + shortest(t_end),
          (from_simulation ? "simulation.trajectory_step_s = " : "the default trajectory step ") + shortest(traj_step),
          t_end, traj_step, "samples of the zero-order motion", lim::kMaxTrajectorySamples,
          "shorten simulate_until_s or raise [simulation] trajectory_step_s");
  }
  if (have_end && horizon && st.closed_loop_first_order_method == ClosedLoopMethod::Gauss) {
    // the Gauss closed loop's work: steps per interval of the gain grid and the outputs
    const double out_step = d.simulation ? d.simulation->options.output_step_s : 0.005;
    const double intervals = std::ceil(st.horizon_s / st.grid_step_s) + std::ceil(st.simulate_until_s / out_step);
    const double n = 2.0 * (3 + d.noa), work = intervals * st.closed_loop_gauss_steps * std::pow(5.0 * n, 3);
    if (work > lim::kMaxGaussWork)
      c.problem(gauss_steps ? "closed_loop_gauss_steps" : "closed_loop_first_order_method",
                c.key_path("closed_loop_first_order_method") + " = \"gauss\" with closed_loop_gauss_steps = " +
                    std::to_string(st.closed_loop_gauss_steps) + " over " + shortest(intervals) +
                    " intervals (gain grid and outputs) at noa = " + std::to_string(d.noa) + " is " + shortest(work) +
                    " units of work (steps x (10 (3 + noa))³); at most " + shortest(lim::kMaxGaussWork) +
                    ": lower closed_loop_gauss_steps, raise grid_step_s or use \"cvodes\"");
  }
  if (d.maneuver) {
    for (int a : d.maneuver->problem.actuators)
      if (std::find(st.actuators.begin(), st.actuators.end(), a) == st.actuators.end())
        c.problem("actuators", c.key_path("actuators") + " must include every maneuver actuator (the feedback adds "
                                                         "to their commands); \"" +
                                   d.actuators[a - d.loads.size()].element.name + "\" is missing");
  }
  d.controller = st;
}


}  // namespace freeflex::io_detail
