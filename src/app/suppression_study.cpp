// [controller] and [bang_bang]: TV-LQR designed on the first-order model about the nominal
// motion (the loads' zero-order motion or the optimized maneuver; control/suppression.hpp
// runs the chain), evaluated on the first-order and the full nonlinear model against the
// open loop and bang-bang rotations: the study, comparison.csv with the cases' histories
// and the figure, and its summary entry.
#include <cmath>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include "app/study_files.hpp"
#include "freeflex/app/progress.hpp"
#include "freeflex/control/lqr.hpp"
#include "freeflex/io/plot.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string num(double v) { return std::isnan(v) ? "" : util::format_number(v, 10); }

/// Element commands at the output times: the loads' profiles plus the given actuator
/// commands (columns in the order of `actuators`).
Eigen::MatrixXd element_commands(const Excitation& ex, int elements, const Eigen::VectorXd& t,
                                 const std::vector<int>& actuators, const Eigen::MatrixXd* actuator_commands) {
  Eigen::MatrixXd c(t.size(), elements);
  for (int i = 0; i < t.size(); ++i) {
    c.row(i) = ex.commands(Instant::at(t(i))).transpose();
    if (actuator_commands)
      for (std::size_t k = 0; k < actuators.size(); ++k) c(i, actuators[k]) = (*actuator_commands)(i, k);
  }
  return c;
}

/// The simulation settings of the comparison runs: the [simulation] section's, else a
/// 5 ms output step at rtol 1e-10. (On the paper's moment pulse the full model's residual
/// E_vib(3 s) is 0.26-0.28 J at rtol 1e-8, moving with round-off, 0.28271 at 1e-9 and
/// 0.28277 at 1e-10.)
SimulationOptions comparison_options(const Design& design) {
  SimulationOptions sim = design.simulation ? design.simulation->options : SimulationOptions{};
  sim.duration_s = design.controller->simulate_until_s;
  if (!design.simulation) {
    sim.output_step_s = 0.005;
    sim.integrator.rtol = 1e-10;
    sim.integrator.atol = 1e-12;
  }
  return sim;
}

/// Progress lines of the chain's phases on the log.
SuppressionOptions with_progress(SuppressionOptions o, std::ostream* log, std::unique_ptr<ProgressReport>& report) {
  if (!log) return o;
  o.on_phase = [log, &report](SuppressionPhase phase, bool done, double total_s, const SuppressionResult& so_far) {
    if (!done) {
      if (phase == SuppressionPhase::OpenLoop) *log << "suppression: open loop (perturbation and full model) ... ";
      if (phase == SuppressionPhase::Tvlqr) *log << "suppression: TV-LQR over " << total_s << " s ... ";
      if (phase == SuppressionPhase::ClosedLoop)
        *log << "suppression: closed loop on the first-order and the full model ... ";
      *log << std::flush;
      report = std::make_unique<ProgressReport>(log, total_s);
      return;
    }
    *log << report->resume();
    if (phase == SuppressionPhase::Tvlqr)
      *log << (so_far.law.ok() ? "done" : "FAILED") << " (" << std::fixed << std::setprecision(3)
           << so_far.law.wall_time_s << " s)" << std::defaultfloat << '\n';
    else
      *log << "done\n";
  };
  o.progress = [&report](SuppressionPhase, double covered) {
    if (report) report->update(covered);
  };
  return o;
}

/// Bang-bang rotations whose switch times leave the first k modes at rest, in place of
/// the nominal maneuver's loads: same rotation, same torque level.
void run_bang_bang(const Design& design, const FlexibleBody& body, const SimulationOptions& sim,
                   SuppressionStudyResult& r, const StudyLog& study_log, std::vector<std::string>& not_run,
                   std::vector<SuppressionStudyResult::Case>* tight) {
  const BangBangStudy& bb = *design.bang_bang;
  std::ostream* log = study_log.log;
  const int ne = static_cast<int>(body.elements().size());
  const double t_end = design.controller->simulate_until_s;
  auto warn = [&](const std::string& why) {
    r.status = StudyStatus::Failed;
    r.message = r.message.empty() ? why : r.message + "; " + why;
    r.warnings.push_back(why);
    if (study_log.warn) study_log.warn(why);
  };
  const double rotation = r.chain.nominal->at(Instant::at(t_end)).pos(2);
  const double limit = design.actuators[static_cast<std::size_t>(bb.actuator) - design.loads.size()].limit;
  // The design refuses what it can tell up front; an inertial force's moment depends on
  // the attitude it produces, so only the simulated rotation can show it is not positive.
  const bool turns = std::isfinite(rotation) && rotation > 0.0;
  if (!turns) {
    const std::string why = "the nominal motion turns the beam by " + num(rotation) + " rad by t = " + num(t_end) +
                            " s; bang-bang rotations need a positive angle";
    r.bang_bang.push_back({std::nullopt, why, std::nullopt});
    warn("[bang_bang]: " + why + ", so none was designed");
    return;
  }
  for (int k : bb.modes) {
    if (sim.integrator.budget && sim.integrator.budget->exhausted()) {
      not_run.push_back("the bang-bang rotation for " + std::to_string(k) + " mode(s)");
      r.bang_bang.push_back({k, "not designed: " + sim.integrator.budget->spent_message(), std::nullopt});
      continue;
    }
    SwitchTimeOptions so;
    so.budget = sim.integrator.budget;  // its simulations are charged to the study's work budget
    if (log) *log << "suppression: bang-bang switch times for " << k << " mode(s) (NLopt) ... " << std::flush;
    ProgressReport progress(log, 0.0);
    so.progress = [&progress](int sims) { progress.note(std::to_string(sims) + " first-order simulations"); };
    const SwitchTimeResult sw = design_switch_times(body, bb.actuator, rotation, limit, k, so);
    // T to 6 digits: the designs lie within 0.1% of T* (the stream prints 3)
    if (log) *log << progress.resume() << (sw.ok() ? "done" : "FAILED") << ", duration "
                  << util::format_number(sw.duration_s, 6) << " s (rigid T* " << util::format_number(sw.rigid_duration_s, 6)
                  << " s), residual/rigid peak " << sw.residual_ratio << '\n';
    r.bang_bang.push_back({k, sw.ok() ? "ok" : sw.message, sw});
    if (!sw.ok()) {
      warn("bang-bang design for " + std::to_string(k) + " modes did not converge: " + sw.message);
      continue;
    }
    Excitation ex;
    ex.profiles.assign(static_cast<std::size_t>(ne), std::nullopt);
    ex.profiles[static_cast<std::size_t>(bb.actuator)] = sw.torque_profile();
    const PerturbationResult bp = simulate_perturbation(body, ex, sim);
    const SimulationResult bf = simulate_full(body, ex, sim);
    const std::string name = "bang_bang_k" + std::to_string(k);
    if (bp.total.ok())
      r.cases.push_back({name, "first_order", bp.total.t, bp.total.z, bp.total.z_dot,
                         element_commands(ex, ne, bp.total.t, {}, nullptr), 0.0, {}});
    else
      warn(name + " perturbation simulation failed: " + bp.total.message);
    if (bf.ok())
      r.cases.push_back(
          {name, "nonlinear", bf.t, bf.z, bf.z_dot, element_commands(ex, ne, bf.t, {}, nullptr), 0.0, {}});
    else
      warn(name + " full simulation failed: " + bf.message);
    if (!tight) continue;
    // the same flights at 10x tighter tolerances, for their error estimates
    if (sim.integrator.budget && sim.integrator.budget->exhausted()) {
      not_run.push_back("the error estimate (" + name + " at 10x tighter tolerances)");
      continue;
    }
    SimulationOptions st = sim;
    st.integrator.rtol /= 10.0;
    st.integrator.atol /= 10.0;
    const PerturbationResult tp = simulate_perturbation(body, ex, st);
    const SimulationResult tf = simulate_full(body, ex, st);
    if (tp.total.ok())
      tight->push_back({name, "first_order", tp.total.t, tp.total.z, tp.total.z_dot,
                        element_commands(ex, ne, tp.total.t, {}, nullptr), 0.0, {}});
    if (tf.ok())
      tight->push_back({name, "nonlinear", tf.t, tf.z, tf.z_dot, element_commands(ex, ne, tf.t, {}, nullptr), 0.0, {}});
    for (const auto& [model, run] : {std::pair<const char*, const SimulationResult*>{"first_order", &tp.total},
                                     {"nonlinear", &tf}}) {
      if (run->ok()) continue;
      if (sim.integrator.budget && sim.integrator.budget->exhausted()) {
        not_run.push_back("the error estimate (" + name + ", " + model + ", at 10x tighter tolerances, stopped)");
      } else {
        const std::string w = "suppression: no error estimate for " + name + " (" + model +
                              "): at 10x tighter tolerances it failed: " + run->message;
        r.warnings.push_back(w);
        if (study_log.warn) study_log.warn(w);
      }
    }
  }
}

}  // namespace

SuppressionStudyResult run_suppression_study(const Design& design, const ManeuverStudyResult* maneuver,
                                             const StudyLog& study_log) {
  const ControllerStudy& st = *design.controller;
  const FlexibleBody body = design.body();
  const int ne = static_cast<int>(body.elements().size());
  std::ostream* log = study_log.log;
  SuppressionStudyResult r;
  auto fail = [&](const std::string& why) {
    r.status = StudyStatus::Failed;
    r.message = r.message.empty() ? why : r.message + "; " + why;
    r.warnings.push_back(why);
    if (study_log.warn) study_log.warn(why);
  };

  SuppressionProblem problem;
  problem.loads = design.excitation();
  if (maneuver && maneuver->flown) problem.maneuver = maneuver->flown;
  problem.actuators = st.actuators;
  problem.limits = st.limits;
  problem.Q = vibration_weight(body, st.weight_elastic, st.weight_rigid_position, st.weight_rigid_rate);
  problem.R = st.input_weights.asDiagonal();
  problem.horizon_s = st.horizon_s;
  problem.until_s = st.simulate_until_s;
  SuppressionOptions options;
  options.simulation = comparison_options(design);
  options.tvlqr.grid_step_s = st.grid_step_s;
  options.tvlqr.method = st.tvlqr_method;
  options.closed_loop.rtol = st.closed_loop_rtol;
  options.closed_loop.atol = st.closed_loop_atol;
  options.closed_loop_first_order_method = st.closed_loop_first_order_method;
  options.closed_loop_gauss_steps = st.closed_loop_gauss_steps;
  // every integration of the study (open and closed loops, the TV-LQR's Riccati sweep, the
  // rigid optimum's chain, the bang-bang designs and runs) is charged to one work budget
  const auto budget = std::make_shared<WorkBudget>(design.study_work, "the [controller] study");
  options.simulation.integrator.budget = options.tvlqr.budget = options.closed_loop.budget = budget;
  std::vector<std::string> not_run;  // what the study left out once the budget was spent
  r.work_budget_units = budget->total();
  std::unique_ptr<ProgressReport> report;
  r.chain = suppress_vibration(body, problem, with_progress(options, log, report));
  r.work_units = budget->spent();  // the study may end here
  const SuppressionResult& chain = r.chain;
  using Status = SuppressionResult::Status;
  if (chain.status == Status::HorizonTooShort) {
    // A fixed duration was checked with the design; a free one is the optimizer's choice.
    fail("controller.horizon_s = " + num(st.horizon_s) + " is shorter than the optimized maneuver (" +
         num(problem.maneuver->duration_s) + " s): no feedback was designed; raise horizon_s to at least "
         "maneuver.duration_max_s");
    return r;
  }
  if (chain.status == Status::OpenLoopFailed) {
    r.status = StudyStatus::Failed;  // not a warning: the run's message says it
    r.message = chain.message;
    return r;
  }
  // The cases of one chain: its open loop and its closed loops, names prefixed, appended to
  // `to`; the chain's failures are the study's when `report`.
  using Case = SuppressionStudyResult::Case;
  auto chain_cases = [&](const SuppressionResult& ch, const SuppressionProblem& pr, const std::string& prefix,
                         std::vector<Case>& to, bool report) {
    const Excitation nominal_ex = pr.maneuver ? pr.maneuver->driving(pr.loads) : pr.loads;
    const PerturbationResult& pert = ch.open_loop_first_order;
    const SimulationResult& full = ch.open_loop_full;
    to.push_back({prefix + "open_loop", "first_order", pert.total.t, pert.total.z, pert.total.z_dot,
                  element_commands(nominal_ex, ne, pert.total.t, {}, nullptr), 0.0, {}});
    to.push_back({prefix + "open_loop", "nonlinear", full.t, full.z, full.z_dot,
                  element_commands(nominal_ex, ne, full.t, {}, nullptr), 0.0, {}});
    if (ch.status == Status::TvlqrFailed) {
      if (report) fail(prefix + ch.message);
      return false;
    }
    for (const ClosedLoopResult* c : {&ch.closed_loop_first_order, &ch.closed_loop_full}) {
      if (!c->ok()) {
        if (report) fail(prefix + "closed-loop simulation failed: " + c->message);
        continue;
      }
      to.push_back({prefix + "tvlqr", c == &ch.closed_loop_first_order ? "first_order" : "nonlinear", c->t, c->z,
                    c->z_dot, element_commands(pr.loads, ne, c->t, st.actuators, &c->commands), c->saturated_fraction,
                    {}});
    }
    return true;
  };
  // A vibration-aware maneuver is compared with its rigid optimum, both with TV-LQR.
  const bool vibration_aware = maneuver && maneuver->rigid_optimum;
  const std::string main_prefix = vibration_aware ? "vibration_aware_" : "";
  if (!chain_cases(chain, problem, main_prefix, r.cases, true)) return r;
  // A chain again at 10x tighter tolerances: how far its energies are from converged.
  // Its cases (named as the chain's) go to `again`.
  std::vector<Case> again;
  auto tight_chain = [&](const SuppressionProblem& pr, const std::string& prefix, const std::string& which) {
    if (budget->exhausted()) {
      not_run.push_back("the error estimate (" + which + " at 10x tighter tolerances)");
      return;
    }
    SuppressionOptions o = options;
    o.simulation.integrator.rtol /= 10.0;
    o.simulation.integrator.atol /= 10.0;
    o.tvlqr.rtol /= 10.0;
    o.tvlqr.atol /= 10.0;
    o.closed_loop.rtol /= 10.0;
    o.closed_loop.atol /= 10.0;
    o.closed_loop_gauss_steps = std::min(2 * o.closed_loop_gauss_steps, 1000);  // the key's bound
    if (log) *log << "suppression: " << which << " at 10x tighter tolerances, for the error estimate ... " << std::flush;
    const SuppressionResult tight = suppress_vibration(body, pr, o);
    if (log) *log << (tight.status == Status::Solved ? "done\n" : "did not complete: " + tight.message + "\n");
    if (tight.status != Status::Solved) {
      if (budget->exhausted()) {
        not_run.push_back("the error estimate (" + which + " at 10x tighter tolerances, stopped)");
      } else {
        r.warnings.push_back("suppression: no error estimate for " + which +
                             ": at 10x tighter tolerances it did not complete: " + tight.message);
        if (study_log.warn) study_log.warn(r.warnings.back());
      }
      return;
    }
    chain_cases(tight, pr, prefix, again, false);
  };
  if (st.error_estimate) tight_chain(problem, main_prefix, "the chain");
  if (vibration_aware && !maneuver->rigid_flown)
    fail("the rigid counterpart of the maneuver did not solve: no rigid_optimum rows");
  if (vibration_aware && maneuver->rigid_flown && budget->exhausted()) not_run.push_back("the rigid optimum's chain");
  if (vibration_aware && maneuver->rigid_flown && !budget->exhausted()) {
    SuppressionProblem rp = problem;
    rp.maneuver = maneuver->rigid_flown;
    if (log) *log << "suppression: the rigid optimum, for comparison\n";
    r.rigid_chain = suppress_vibration(body, rp, with_progress(options, log, report));
    if (r.rigid_chain->status == Status::HorizonTooShort || r.rigid_chain->status == Status::OpenLoopFailed)
      fail("rigid optimum: " + r.rigid_chain->message);
    else if (chain_cases(*r.rigid_chain, rp, "rigid_optimum_", r.cases, true) && st.error_estimate)
      tight_chain(rp, "rigid_optimum_", "the rigid optimum's chain");
  }
  if (design.bang_bang)
    run_bang_bang(design, body, options.simulation, r, study_log, not_run, st.error_estimate ? &again : nullptr);
  if (!not_run.empty()) {
    std::string list;
    for (const auto& w : not_run) list += (list.empty() ? "" : ", ") + w;
    fail(budget->spent_message() + ": not run: " + list);
  }
  r.work_units = budget->spent();

  // Metrics of every case against the nominal motion's end.
  MetricTargets targets;
  const RigidState end = chain.nominal->at(Instant::at(st.simulate_until_s));
  targets.R_target = end.pos.head<2>();
  targets.theta_target = end.pos(2);
  for (auto& c : r.cases) c.metrics = response_metrics(body, c.t, c.z, c.z_dot, c.commands, targets);
  if (!again.empty()) {
    // energies below 1e-10 of the open loop's residual are zero to the integrations'
    // accuracy: their changes are not a convergence question
    // (per chain: the rigid optimum's rows against its own open loop, the rest against the
    // main chain's)
    auto open_loop_floor = [&](const std::string& prefix) {
      double f = 0.0;
      for (const Case& c : r.cases)
        if (c.name == prefix + "open_loop") f = std::max(f, 1e-10 * c.metrics.residual_vibration_energy_J);
      return f;
    };
    const double main_floor = open_loop_floor(main_prefix), rigid_floor = open_loop_floor("rigid_optimum_");
    for (Case& c : r.cases) {
      const double floor = c.name.rfind("rigid_optimum_", 0) == 0 ? rigid_floor : main_floor;
      const auto twin = std::find_if(again.begin(), again.end(),
                                     [&](const Case& a) { return a.name == c.name && a.model == c.model; });
      if (twin == again.end()) continue;  // its closed loop failed at the tighter tolerances
      const ResponseMetrics m = response_metrics(body, twin->t, twin->z, twin->z_dot, twin->commands, targets);
      c.energy_error_estimate_J = std::abs(m.residual_vibration_energy_J - c.metrics.residual_vibration_energy_J);
      if (detail::energy_not_converged(c.energy_error_estimate_J, c.metrics.residual_vibration_energy_J, floor)) {
        std::ostringstream os;
        os << "suppression: the " << c.name << " (" << c.model << ") residual vibration energy "
           << c.metrics.residual_vibration_energy_J << " J moves by " << c.energy_error_estimate_J
           << " J at 10x tighter tolerances: not converged; tighten [simulation] rtol/atol or "
              "[controller] closed_loop_rtol/closed_loop_atol";
        r.warnings.push_back(os.str());
        if (study_log.warn) study_log.warn(r.warnings.back());
      }
    }
  }
  if (log) {
    *log << "  case          model         E_vib(end) [J]  mean, last 1 s [J]   peak tip [m]   effort [N^2 s]\n";
    for (const auto& c : r.cases) {
      const ResponseMetrics& m = c.metrics;
      *log << "  " << std::left << std::setw(14) << c.name << std::setw(14) << c.model << std::right << std::setw(14)
           << std::setprecision(4) << m.residual_vibration_energy_J << std::setw(20) << m.mean_vibration_energy_J
           << std::setw(15) << m.peak_tip_deflection_m << std::setw(17) << m.control_effort << '\n';
    }
  }
  return r;
}

namespace detail {

void write_suppression(const Design& design, const SuppressionStudyResult& r, RunOutput& out) {
  const ControllerStudy& st = *design.controller;
  if (r.cases.empty() || r.chain.status == SuppressionResult::Status::TvlqrFailed) return;
  const FlexibleBody body = design.body();
  std::ostringstream csv;
  csv << "case,model,residual_vibration_energy_J,peak_tip_deflection_m,tip_settling_time_s,final_position_error_m,"
         "final_attitude_error_rad,control_effort_N2s,peak_command,saturated_fraction,mean_vibration_energy_J\n";
  PlotSpec fig{st.figure, "Vibration suppression: " + design.title,
               {{"tip deflection (right end)", "t [s]", "deflection [m]", {}},
                {"vibration energy (log scale; the key gives each case's energy at t = " + num(st.simulate_until_s) + " s)", "t [s]", "E_vib [J]", {}, true}}};
  const Eigen::RowVectorXd phi_l = body.basis().value(body.beam().x_left());
  const Eigen::RowVectorXd phi_r = body.basis().value(body.beam().x_right());
  const int n = body.n();
  // each case its own colour, in every panel and in the commands' figure; the model told
  // apart by the dash (first order dashed, nonlinear solid)
  std::vector<std::string> case_names;
  for (const auto& c : r.cases)
    if (std::find(case_names.begin(), case_names.end(), c.name) == case_names.end()) case_names.push_back(c.name);
  auto color = [&](const std::string& name) {
    return series_color(static_cast<std::size_t>(std::find(case_names.begin(), case_names.end(), name) -
                                                 case_names.begin()));
  };
  auto style = [](const SuppressionStudyResult::Case& c) {
    return c.model == "nonlinear" ? std::string("lines") : std::string("lines dt 2");
  };
  for (const auto& c : r.cases) {
    const ResponseMetrics& m = c.metrics;
    csv << c.name << ',' << c.model << ',' << num(m.residual_vibration_energy_J) << ','
        << num(m.peak_tip_deflection_m) << ',' << num(m.tip_settling_time_s) << ',' << num(m.final_position_error_m)
        << ',' << num(m.final_attitude_error_rad) << ',' << num(m.control_effort) << ',' << num(m.peak_command) << ','
        << num(c.saturated_fraction) << ',' << num(m.mean_vibration_energy_J) << '\n';
    // history for the figure
    Eigen::MatrixXd h(c.t.size(), 4);
    for (int i = 0; i < c.t.size(); ++i) {
      const Eigen::VectorXd q = c.z.row(i).tail(n).transpose(), qd = c.z_dot.row(i).tail(n).transpose();
      h(i, 0) = c.t(i);
      h(i, 1) = phi_l.dot(q);
      h(i, 2) = phi_r.dot(q);
      h(i, 3) = body.vibration_energy(q, qd);
    }
    const std::string file = "case_" + c.name + "_" + c.model + ".csv";
    out.csv(file, {"t", "tip_left_m", "tip_right_m", "vibration_energy_J"}, h);
    const std::string label = c.name + " (" + c.model + ")";
    fig.panels[0].series.push_back({file, 1, 3, label, style(c), true, color(c.name)});
    std::ostringstream energy_label;  // what the figure shows: the energy each case leaves
    energy_label << label << " " << std::setprecision(3) << m.residual_vibration_energy_J << " J";
    fig.panels[1].series.push_back({file, 1, 4, energy_label.str(), style(c), true, color(c.name)});
  }
  out.write("comparison.csv", csv.str());
  out.plot(fig, design.plots);

  // the commands of the feedback actuators against their limits: open loop (the nominal
  // commands) and under the TV-LQR
  PlotSpec cmd{st.figure + "_commands", "Feedback actuators' commands, open loop and under TV-LQR: " + design.title, {}};
  const std::vector<ForceElement> elements = design.force_elements();
  for (std::size_t k = 0; k < st.actuators.size(); ++k) {
    PlotPanel p{st.actuator_names[k] + " (element " + std::to_string(st.actuators[k]) + ")", "t [s]",
                "command [N or N m]", {}};
    if (std::isfinite(st.limits(static_cast<Eigen::Index>(k)))) {
      p.hlines = {-st.limits(static_cast<Eigen::Index>(k)), st.limits(static_cast<Eigen::Index>(k))};
      p.hline_title = "limits";
    }
    cmd.panels.push_back(p);
  }
  // every nominal's open loop and TV-LQR (a vibration-aware maneuver adds its rigid
  // optimum's): with more than one nominal, the nonlinear model's only, to stay readable
  auto ends_with = [](const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
  };
  const bool several = r.rigid_chain.has_value();
  for (const auto& c : r.cases) {
    if (!ends_with(c.name, "open_loop") && !ends_with(c.name, "tvlqr")) continue;
    if (several && c.model != "nonlinear") continue;
    Eigen::MatrixXd h(c.t.size(), 1 + static_cast<Eigen::Index>(st.actuators.size()));
    h.col(0) = c.t;
    std::vector<std::string> header{"t"};
    for (std::size_t k = 0; k < st.actuators.size(); ++k) {
      h.col(1 + static_cast<Eigen::Index>(k)) = c.commands.col(st.actuators[k]);
      header.push_back(st.actuator_names[k]);
    }
    const std::string file = "commands_" + c.name + "_" + c.model + ".csv";
    out.csv(file, header, h);
    for (std::size_t k = 0; k < st.actuators.size(); ++k)
      cmd.panels[k].series.push_back(
          {file, 1, 2 + static_cast<int>(k), c.name + " (" + c.model + ")",
           // dash-dot: the rigid optimum's, beside the vibration-aware one it would hide
           several && c.name.rfind("rigid_optimum_", 0) == 0 ? "lines dt 4" : style(c), true, color(c.name)});
  }
  out.plot(cmd, design.plots);
}

Json to_json(const Design& design, const SuppressionStudyResult& r) {
  using Status = SuppressionResult::Status;
  const SuppressionResult& chain = r.chain;
  if (chain.status == Status::OpenLoopFailed) return Json();
  Json js = Json::object();
  if (chain.status == Status::HorizonTooShort) {
    js["status"] = "horizon shorter than the maneuver";
    return js;
  }
  Json actuators = Json::array();
  for (const auto& name : design.controller->actuator_names) actuators.push_back(name);
  js["actuators"] = actuators;
  js["horizon_s"] = design.controller->horizon_s;
  js["work_units"] = r.work_units;  // of the study's budget (README, the "(limits)" row)
  js["work_budget_units"] = r.work_budget_units;
  js["tvlqr_status"] = chain.law.ok() ? "ok" : chain.law.message;
  js["tvlqr_solve_time_s"] = chain.law.wall_time_s;
  js["tvlqr_method"] = to_string(chain.law.method);  // the one used ("auto" resolved)
  js["tvlqr_steps"] = chain.law.steps;
  if (r.rigid_chain) js["rigid_optimum_tvlqr_status"] = r.rigid_chain->law.ok() ? "ok" : r.rigid_chain->law.message;
  if (chain.law.terminal_care) {
    js["terminal_care_residual"] = chain.law.terminal_care->residual;
    js["terminal_care_residual_normwise"] = chain.law.terminal_care->residual_normwise;
  }
  if (!chain.law.ok()) return js;
  if (design.bang_bang) {
    Json jb = Json::array();
    for (const auto& b : r.bang_bang) {
      Json e = Json::object();
      if (b.modes) e["modes"] = *b.modes;
      e["status"] = b.status;
      if (b.design) {
        e["duration_s"] = b.design->duration_s;
        e["rigid_duration_s"] = b.design->rigid_duration_s;
        e["residual_ratio"] = b.design->residual_ratio;
        Json times = Json::array();
        for (double t : b.design->switch_times) times.push_back(t);
        e["switch_times_s"] = times;
      }
      jb.push_back(e);
    }
    js["bang_bang"] = jb;
  }
  Json table = Json::array();
  for (const auto& c : r.cases) {
    const ResponseMetrics& m = c.metrics;
    Json row = Json::object();
    row["case"] = c.name;
    row["model"] = c.model;
    row["residual_vibration_energy_J"] = m.residual_vibration_energy_J;
    if (std::isfinite(c.energy_error_estimate_J))
      row["residual_vibration_energy_error_estimate_J"] = c.energy_error_estimate_J;  // 10x tighter tolerances
    row["peak_tip_deflection_m"] = m.peak_tip_deflection_m;
    row["tip_settling_time_s"] = m.tip_settling_time_s;
    row["final_attitude_error_rad"] = m.final_attitude_error_rad;
    row["final_position_error_m"] = m.final_position_error_m;
    row["control_effort_N2s"] = m.control_effort;
    row["peak_command"] = m.peak_command;
    row["saturated_fraction"] = c.saturated_fraction;
    row["mean_vibration_energy_J"] = m.mean_vibration_energy_J;
    table.push_back(row);
  }
  js["cases"] = table;
  return js;
}

}  // namespace detail
}  // namespace freeflex
