// [maneuver]: an optimal rigid maneuver (zero-order model, direct collocation, Ipopt):
// the study, trajectory.csv with its figures and Ipopt's log, and its summary entry. It
// hands [simulation] and [controller] the maneuver to fly.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>

#include "app/study_files.hpp"
#include "freeflex/io/plot.hpp"

namespace freeflex {
namespace {

/// [maneuver.ipopt] output_file names a file in the run's directory (the design checked
/// the name); "" when not given.
std::string ipopt_output_file(const TrajoptOptions& options) {
  for (const auto& [key, value] : options.ipopt_options)
    if (key == "output_file") return value;
  return "";
}

/// What the optimized maneuver is, for its figures' titles: "rigid-body optimum" or
/// "vibration-aware optimum: 4 elastic modes, all at rest", then "; objective: ..." (the
/// terms of the objective with a weight).
std::string maneuver_kind(const ManeuverProblem& p) {
  std::ostringstream os;
  if (p.elastic) {
    os << "vibration-aware optimum: ";
    if (p.elastic_modes > 0)
      os << p.elastic_modes << " elastic mode" << (p.elastic_modes == 1 ? "" : "s");
    else
      os << "first-order elastic model";
    if (p.modes_at_rest == ManeuverProblem::all_modes)
      os << ", all at rest";
    else if (p.modes_at_rest > 0)
      os << ", first " << p.modes_at_rest << " at rest";
    if (std::isfinite(p.tip_deflection_limit_m)) os << ", tip deflection <= " << p.tip_deflection_limit_m << " m";
  } else {
    os << "rigid-body optimum";
  }
  std::vector<std::string> terms;
  if (p.w_time > 0) terms.push_back("time");
  if (p.w_energy > 0) terms.push_back("command energy");
  if (p.w_smooth > 0) terms.push_back("command rate");
  if (p.elastic && p.w_vibration > 0) terms.push_back("residual vibration");
  for (std::size_t i = 0; i < terms.size(); ++i) os << (i ? " + " : "; objective: ") << terms[i];
  return os.str();
}

}  // namespace

ManeuverStudyResult run_maneuver_study(const Design& design, bool quiet, const StudyLog& study_log) {
  const ManeuverStudy& st = *design.maneuver;
  const FlexibleBody body = design.body();
  std::ostream* log = study_log.log;
  TrajoptOptions opt = st.options;
  opt.verbose = !st.quiet && !quiet && log != nullptr;
  if (log)
    *log << "maneuver: " << to_string(opt.transcription) << ", " << opt.intervals << " intervals, "
         << (st.problem.free_time ? "free" : "fixed") << " duration" << (opt.verbose ? " (Ipopt log follows)" : " ...")
         << std::endl;
  // the checker prints nothing until it ends, quiet or not: say what it is doing (its work
  // is bounded by the design, design_limits::kMaxDerivativeTestUnknowns)
  if (log && opt.derivative_test != "none")
    *log << "maneuver: Ipopt's " << opt.derivative_test << " derivative test on the first mesh ..." << std::endl;
  // Ipopt would rewrite its output_file at each solve, keeping the last mesh-refinement
  // round only: freeflex collects the log of every round and writes it itself.
  for (auto it = opt.ipopt_options.begin(); it != opt.ipopt_options.end();) {
    if (it->first == "output_file") {
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
  if (!ipopt_output_file(st.options).empty()) opt.keep_log = true;
  ManeuverStudyResult r;
  const ManeuverProblem rigid = rigid_counterpart(st.problem);  // used when elastic
  if (st.problem.elastic) {
    // The rigid optimum of the same objective, solved first: what the vibration-aware
    // maneuver costs, and its starting point (TrajoptOptions::coarse_start, here on
    // the full mesh since it is solved anyway).
    if (log) *log << "maneuver: rigid counterpart (no elastic part), for comparison and as the starting point ... "
                  << std::flush;
    TrajoptOptions ro = opt;
    ro.verbose = false;
    r.rigid_optimum = solve_maneuver(body, rigid, ro);
    if (log) *log << to_string(r.rigid_optimum->status) << " after " << r.rigid_optimum->iterations << " iterations\n";
    // the elastic problem starts from it (coarse_start), here on the full mesh since it is
    // solved anyway; coarse_start = false: from the straight line
    const bool start_from_it = opt.coarse_start;
    opt.coarse_start = false;
    if (r.rigid_optimum->ok()) {
      if (start_from_it) opt.guess.solution = r.rigid_optimum->trajectory;
    } else {
      r.warnings.push_back("maneuver: the rigid counterpart did not solve (" +
                           std::string(to_string(r.rigid_optimum->status)) + "): " + r.rigid_optimum->message);
      if (study_log.warn) study_log.warn(r.warnings.back());
    }
  }
  r.trajopt = solve_maneuver(body, st.problem, opt);
  const TrajoptResult& t = r.trajopt;
  if (log)
    *log << "maneuver: " << to_string(t.status) << " after " << t.iterations << " iterations"
         << (t.warm_started ? " (and " + std::to_string(t.warm_start_iterations) + " on the coarse mesh)" : std::string())
         << ", " << std::fixed
         << std::setprecision(3) << t.solve_time_s << " s; objective " << std::defaultfloat << t.objective
         << ", duration " << t.duration_s << " s, max defect " << t.max_defect << '\n';
  if (!t.ok()) {
    r.status = StudyStatus::Failed;
    r.message = "maneuver optimization did not succeed (" + std::string(to_string(t.status)) + "): " + t.message +
                "; no trajectory was written";
    r.warnings.push_back(r.message);
    if (study_log.warn) study_log.warn(r.message);
    return r;
  }
  r.status = StudyStatus::Ok;
  r.flown = flown_maneuver(t, st.problem);
  r.chattering = detect_chattering(t, st.problem);
  if (r.chattering.flagged) {
    r.warnings.push_back("maneuver: " + r.chattering.message + "; " + r.chattering.remedy);
    if (study_log.warn) study_log.warn(r.warnings.back());
  }
  r.replay = check_replay(body, st.problem, t);
  if (!r.replay->ok || r.replay->flagged) {
    r.warnings.push_back("maneuver: " + r.replay->message);
    if (study_log.warn) study_log.warn(r.warnings.back());
  }
  if (!t.unresolved_modes.empty()) {
    r.warnings.push_back("maneuver: " + unresolved_modes_message(t));
    if (study_log.warn) study_log.warn(r.warnings.back());
  }
  if (st.problem.elastic) {
    if (r.rigid_optimum->ok()) {
      if (log) *log << "maneuver: control energy " << t.control_energy << " against the rigid counterpart's "
                    << r.rigid_optimum->control_energy << '\n';
      r.rigid_flown = flown_maneuver(*r.rigid_optimum, rigid);
    }
  }
  return r;
}

namespace detail {

void write_maneuver(const Design& design, const ManeuverStudyResult& r, RunOutput& out) {
  const ManeuverStudy& st = *design.maneuver;
  const TrajoptResult& t = r.trajopt;
  const std::string ipopt_file = ipopt_output_file(st.options);
  if (!ipopt_file.empty()) out.write(ipopt_file, t.log);
  if (!r.ok()) return;
  // Knots (and Hermite-Simpson midpoints) in time order: the solution's own points.
  const int nu = static_cast<int>(st.actuator_names.size());
  std::vector<std::pair<double, int>> rows;  // time, index (>= 0 knot, < 0 midpoint -1-k)
  for (int k = 0; k < t.t.size(); ++k) rows.push_back({t.t(k), k});
  for (int k = 0; k < t.t_mid.size(); ++k) rows.push_back({t.t_mid(k), -1 - k});
  std::sort(rows.begin(), rows.end());
  std::vector<std::string> header{"t", "Rx", "Ry", "theta", "Rx_dot", "Ry_dot", "theta_dot"};
  for (const auto& n : st.actuator_names) header.push_back(n);
  Eigen::MatrixXd data(static_cast<int>(rows.size()), 7 + nu);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto [time, k] = rows[i];
    data(i, 0) = time;
    data.row(i).segment(1, 6) = k >= 0 ? t.x.row(k) : t.x_mid.row(-1 - k);
    data.row(i).tail(nu) = k >= 0 ? t.u.row(k) : t.u_mid.row(-1 - k);
  }
  out.csv("trajectory.csv", header, data);
  // what is drawn: the optimum's rigid-body motion and commands (not the flown or
  // controlled response), and which optimum it is
  const std::string kind = maneuver_kind(st.problem);
  PlotSpec states{"maneuver_states", "Optimized maneuver's rigid-body motion (" + kind + ") — " + design.title, {}};
  const char* names[3] = {"R_x [m]", "R_y [m]", "theta [rad]"};
  // the coordinates that move, as the simulation's figures (theta if none does)
  for (int c = 0; c < 3; ++c)
    if (moves(data.col(1 + c)) || (c == 2 && states.panels.empty()))
      states.panels.push_back({names[c], "t [s]", names[c], {{"trajectory.csv", 1, 2 + c, "optimized", "lines"}}});
  out.plot(states, design.plots);
  PlotSpec controls{"maneuver_controls", "Optimized commands (" + kind + ") — " + design.title,
                    {{"commands", "t [s]", "u [N or N m]", {}}}};
  for (int a = 0; a < nu; ++a)
    controls.panels[0].series.push_back({"trajectory.csv", 1, 8 + a, st.actuator_names[a], "linespoints pt 7 ps 0.4"});
  // the bounds the optimizer was given, so that a command at its limit shows as one
  for (const Eigen::VectorXd* b : {&st.problem.u_min, &st.problem.u_max})
    for (Eigen::Index a = 0; a < b->size(); ++a)
      if (std::isfinite((*b)(a)) &&
          std::find(controls.panels[0].hlines.begin(), controls.panels[0].hlines.end(), (*b)(a)) ==
              controls.panels[0].hlines.end())
        controls.panels[0].hlines.push_back((*b)(a));
  controls.panels[0].hline_title = "command limits";
  if (!controls.panels[0].hlines.empty()) controls.title += " (dotted: the limits)";
  out.plot(controls, design.plots);
}

Json to_json(const ManeuverStudyResult& r) {
  const TrajoptResult& t = r.trajopt;
  Json j = Json::object();
  j["status"] = status_text(t);
  j["message"] = t.message;
  j["objective"] = t.objective;
  j["iterations"] = t.iterations;
  // the coarse solve the optimizer started from (TrajoptOptions::coarse_start; 0: none)
  j["coarse_start_iterations"] = t.warm_start_iterations;
  j["solve_time_s"] = t.solve_time_s;
  j["duration_s"] = t.duration_s;
  j["max_defect"] = t.max_defect;
  j["transcription"] = to_string(t.transcription);
  j["linear_solver"] = to_string(t.linear_solver);
  j["intervals"] = t.intervals;
  if (r.ok()) {
    Json c = Json::object();
    c["flagged"] = r.chattering.flagged;
    c["message"] = r.chattering.message;
    if (r.chattering.flagged) {
      c["remedy"] = r.chattering.remedy;
      c["suggested_smooth_weight"] = r.chattering.suggested_smooth_weight;
      c["suggested_rate_limits"] = std::vector<double>(r.chattering.suggested_rate_limit.data(),
                                                       r.chattering.suggested_rate_limit.data() +
                                                           r.chattering.suggested_rate_limit.size());
    }
    j["chattering"] = c;
  }
  if (r.replay) {
    const ReplayCheck& rc = *r.replay;
    Json c = Json::object();
    c["ok"] = rc.ok;
    c["flagged"] = rc.flagged;
    if (rc.ok) {
      c["position_miss_m"] = rc.position_miss_m;
      c["theta_miss_rad"] = rc.theta_miss_rad;
      c["rate_miss"] = rc.rate_miss;
    }
    if (!rc.message.empty()) c["message"] = rc.message;
    j["replay"] = c;
  }
  if (t.x_elastic.cols() > 0) {
    Json e = Json::object();
    e["terminal_vibration_energy_J"] = t.terminal_vibration_energy_J;  // the optimizer's first-order model
    e["mode_frequencies_rad_s"] = std::vector<double>(t.mode_frequencies.data(),
                                                      t.mode_frequencies.data() + t.mode_frequencies.size());
    e["max_interval_s"] = t.max_interval_s;
    std::vector<int> unresolved;  // 1-based, as modes are numbered everywhere else
    for (int j : t.unresolved_modes) unresolved.push_back(j + 1);
    e["unresolved_modes"] = unresolved;
    e["peak_tip_deflection_m"] = t.peak_tip_deflection_m;              // at the collocation points
    e["control_energy_N2s"] = t.control_energy;  // ∫ uᵀ W u dt of the commands as flown
    if (r.rigid_optimum) {
      const TrajoptResult& ro = *r.rigid_optimum;
      Json jr = Json::object();
      jr["status"] = status_text(ro);
      jr["objective"] = ro.objective;
      jr["duration_s"] = ro.duration_s;
      jr["control_energy_N2s"] = ro.control_energy;
      e["rigid_optimum"] = jr;
      if (ro.ok()) e["extra_control_energy_N2s"] = t.control_energy - ro.control_energy;
    }
    j["elastic"] = e;
  }
  return j;
}

}  // namespace detail
}  // namespace freeflex
