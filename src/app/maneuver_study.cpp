// [maneuver]: an optimal rigid maneuver (zero-order model, direct collocation, Ipopt),
// written as trajectory.csv with figures, and handed to [simulation] as the nominal motion.
#include <cstdlib>
#include <iomanip>

#include "freeflex/app/run.hpp"
#include "freeflex/io/plot.hpp"

namespace freeflex {

void ManeuverOutcome::drive(Excitation& ex) const {
  auto traj = trajectory;
  const std::vector<int> idx = actuators;
  ex.add_commands = [traj, idx](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) {
    if (at.piece_mid > traj->t_end()) return;
    const Eigen::VectorXd u = traj->control_at(at);
    for (std::size_t k = 0; k < idx.size(); ++k) c(idx[k]) += u(static_cast<Eigen::Index>(k));
  };
  const Eigen::VectorXd& knots = traj->knot_times();
  ex.add_breakpoints.assign(knots.data(), knots.data() + knots.size());
  ex.add_end_time = duration_s;
}

std::shared_ptr<const RigidTrajectory> ManeuverOutcome::nominal() const {
  return std::make_shared<ExtendedTrajectory>(trajectory, duration_s);
}

ManeuverOutcome run_maneuver(const Design& design, RunOutput& out, Json& summary, bool quiet) {
  const ManeuverStudy& st = *design.maneuver;
  const FlexibleBody body(Beam(design.beam), design.noa, design.force_elements(), design.damping_ratios);
  TrajoptOptions opt = st.options;
  opt.verbose = !st.quiet && !quiet && out.log() != nullptr;
  std::ostream* log = out.log();
  if (log)
    *log << "maneuver: " << to_string(opt.transcription) << ", " << opt.intervals << " intervals, "
         << (st.problem.free_time ? "free" : "fixed") << " duration" << (opt.verbose ? " (Ipopt log follows)" : " ...")
         << std::endl;
  // [maneuver.ipopt] output_file names a file in the run's directory (the design checked
  // the name). Ipopt would rewrite it at each solve, keeping the last mesh-refinement round
  // only: freeflex collects the log of every round and writes it itself.
  std::string ipopt_file;
  for (auto it = opt.ipopt_options.begin(); it != opt.ipopt_options.end();) {
    if (it->first == "output_file") {
      ipopt_file = it->second;
      it = opt.ipopt_options.erase(it);
      continue;
    }
    if (it->first == "file_print_level") {  // still passed on: Ipopt checks the value
      char* end = nullptr;
      const long level = std::strtol(it->second.c_str(), &end, 10);
      if (end && *end == '\0' && level >= 0 && level <= 12) opt.log_level = static_cast<int>(level);
    }
    ++it;
  }
  if (!ipopt_file.empty()) opt.keep_log = true;
  const TrajoptResult r = solve_maneuver(body, st.problem, opt);
  if (!ipopt_file.empty()) out.write(ipopt_file, r.log);
  if (log)
    *log << "maneuver: " << to_string(r.status) << " after " << r.iterations << " iterations, " << std::fixed
         << std::setprecision(3) << r.solve_time_s << " s; objective " << std::defaultfloat << r.objective
         << ", duration " << r.duration_s << " s, max defect " << r.max_defect << '\n';
  Json j = Json::object();
  j["status"] = r.ok() ? "ok" : to_string(r.status);
  j["message"] = r.message;
  j["objective"] = r.objective;
  j["iterations"] = r.iterations;
  j["solve_time_s"] = r.solve_time_s;
  j["duration_s"] = r.duration_s;
  j["max_defect"] = r.max_defect;
  j["transcription"] = to_string(r.transcription);
  j["intervals"] = r.intervals;
  summary["maneuver"] = j;
  ManeuverOutcome outcome;
  if (!r.ok()) {
    out.warn("maneuver optimization did not succeed (" + std::string(to_string(r.status)) + "): " + r.message +
             "; no trajectory was written");
    outcome.code = kExitNumericalFailure;
    return outcome;
  }
  // Knots (and Hermite-Simpson midpoints) in time order: the solution's own points.
  const int nu = static_cast<int>(st.actuator_names.size());
  std::vector<std::pair<double, int>> rows;  // time, index (>= 0 knot, < 0 midpoint -1-k)
  for (int k = 0; k < r.t.size(); ++k) rows.push_back({r.t(k), k});
  for (int k = 0; k < r.t_mid.size(); ++k) rows.push_back({r.t_mid(k), -1 - k});
  std::sort(rows.begin(), rows.end());
  std::vector<std::string> header{"t", "Rx", "Ry", "theta", "Rx_dot", "Ry_dot", "theta_dot"};
  for (const auto& n : st.actuator_names) header.push_back(n);
  Eigen::MatrixXd data(static_cast<int>(rows.size()), 7 + nu);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto [t, k] = rows[i];
    data(i, 0) = t;
    data.row(i).segment(1, 6) = k >= 0 ? r.x.row(k) : r.x_mid.row(-1 - k);
    data.row(i).tail(nu) = k >= 0 ? r.u.row(k) : r.u_mid.row(-1 - k);
  }
  out.csv("trajectory.csv", header, data);
  PlotSpec states{"maneuver_states", "Optimized rigid maneuver: " + design.title, {}};
  const char* names[3] = {"R_x [m]", "R_y [m]", "theta [rad]"};
  for (int c = 0; c < 3; ++c)
    states.panels.push_back({names[c], "t [s]", names[c], {{"trajectory.csv", 1, 2 + c, "optimized", "lines"}}});
  out.plot(states, design.plots);
  PlotSpec controls{"maneuver_controls", "Actuator commands: " + design.title, {{"commands", "t [s]", "u [N or N m]", {}}}};
  for (int a = 0; a < nu; ++a)
    controls.panels[0].series.push_back({"trajectory.csv", 1, 8 + a, st.actuator_names[a], "linespoints pt 7 ps 0.4"});
  out.plot(controls, design.plots);
  outcome.trajectory = r.trajectory;
  outcome.actuators = st.problem.actuators;
  outcome.duration_s = r.duration_s;
  return outcome;
}

}  // namespace freeflex
