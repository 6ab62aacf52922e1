// [simulation]: forced response with the full nonlinear model and the perturbation
// solution (zero-order then first-order), their differences, energies and momenta (the
// paper's Figs. 4-7): the study, nonlinear.csv and perturbation.csv with their figures,
// and its summary entry.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "app/study_files.hpp"
#include "freeflex/app/progress.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "freeflex/io/plot.hpp"
#include "freeflex/sim/simulate.hpp"

namespace freeflex {
namespace {

/// Columns: t, z, z', tip deflections, vibration energy (+ invariants for the full model).
Eigen::MatrixXd response_table(const FlexibleBody& body, const SimulationResult& r, const FullModel* full,
                               std::vector<std::string>& header) {
  const int n = body.n(), N = body.dofs(), T = static_cast<int>(r.t.size());
  header = {"t", "Rx", "Ry", "theta"};
  for (int i = 1; i <= n; ++i) header.push_back("q" + std::to_string(i));
  for (const char* c : {"Rx_dot", "Ry_dot", "theta_dot"}) header.push_back(c);
  for (int i = 1; i <= n; ++i) header.push_back("q" + std::to_string(i) + "_dot");
  for (const char* c : {"tip_left_m", "tip_right_m", "vibration_energy_J"}) header.push_back(c);
  if (full)
    for (const char* c : {"energy_J", "momentum_x_Ns", "momentum_y_Ns", "angular_momentum_Nms"}) header.push_back(c);
  Eigen::MatrixXd d(T, static_cast<int>(header.size()));
  const Eigen::RowVectorXd phi_l = body.basis().value(body.beam().x_left());
  const Eigen::RowVectorXd phi_r = body.basis().value(body.beam().x_right());
  for (int i = 0; i < T; ++i) {
    const Eigen::VectorXd q = r.z.row(i).tail(n).transpose(), qd = r.z_dot.row(i).tail(n).transpose();
    int c = 0;
    d(i, c++) = r.t(i);
    d.row(i).segment(c, N) = r.z.row(i);
    c += N;
    d.row(i).segment(c, N) = r.z_dot.row(i);
    c += N;
    d(i, c++) = phi_l.dot(q);
    d(i, c++) = phi_r.dot(q);
    d(i, c++) = body.vibration_energy(q, qd);
    if (full) {
      Eigen::VectorXd x(2 * N);
      x << r.z.row(i).transpose(), r.z_dot.row(i).transpose();
      const Eigen::Vector2d p = full->linear_momentum(x);
      d(i, c++) = full->energy(x);
      d(i, c++) = p(0);
      d(i, c++) = p(1);
      d(i, c++) = full->angular_momentum(x);
    }
  }
  return d;
}

/// Largest change over rows with t >= t_from of the quantity in columns [c, c + width),
/// as a vector norm, relative to `scale`.
double drift(const Eigen::MatrixXd& d, int c, int width, double t_from, double scale) {
  Eigen::VectorXd ref;
  double worst = 0.0;
  for (int i = 0; i < d.rows(); ++i) {
    if (d(i, 0) < t_from) continue;
    const Eigen::VectorXd v = d.row(i).segment(c, width).transpose();
    if (ref.size() == 0) ref = v;
    worst = std::max(worst, (v - ref).norm());
  }
  return scale > 0.0 ? worst / scale : 0.0;
}

/// Records a failed run in the study: its reason as a warning and the study's message.
void fail(SimulationStudyResult& r, const StudyLog& study_log, const std::string& why) {
  r.status = StudyStatus::Failed;
  r.message = r.message.empty() ? why : r.message + "; " + why;
  r.warnings.push_back(why);
  if (study_log.warn) study_log.warn(why);
}

/// The second run of the error estimate, its line in the log and, when the estimate is a
/// sizeable part of the motion, a warning that the result is not converged.
template <class Simulate>
GlobalErrorEstimate estimate_error(const char* what, const SimulationResult& run, const SimulationOptions& options,
                                   Simulate simulate, SimulationStudyResult& r, const StudyLog& study_log) {
  std::ostream* log = study_log.log;
  const SimulationOptions tight = error_reference_options(options);
  if (log) *log << "  error estimate: " << what;
  GlobalErrorEstimate e;
  if (tight.integrator.rtol < options.integrator.rtol) {
    if (log) *log << " again at rtol " << tight.integrator.rtol << " ... " << std::flush;
    e = compare_runs(run, simulate(tight), tight);
  } else {
    e.rtol = tight.integrator.rtol;
    e.atol = tight.integrator.atol;
    e.message = "rtol is at the floor of 1e-14: no tighter run to compare with";
  }
  if (!e.available) {
    if (log) *log << " not available (" << e.message << ")\n";
    const std::string w = std::string(what) + ": no global error estimate: " + e.message;
    r.warnings.push_back(w);
    if (study_log.warn) study_log.warn(w);
    return e;
  }
  if (log)
    *log << std::setprecision(2) << "theta " << e.theta_rad << " rad, R " << e.R_m << " m, q " << e.q << " (worst at "
         << std::setprecision(4) << e.worst_time_s << " s; " << std::fixed << std::setprecision(3) << e.wall_time_s
         << " s)" << std::defaultfloat << std::setprecision(6) << '\n';
  // Not converged: an error of 1% of the largest excursion of R or q, or of 0.01 rad in θ;
  // an error below 100 atol (the design's own scale of an insignificant error) never is,
  // so that a coordinate that stays at zero up to round-off raises nothing.
  const double R_peak = run.z.leftCols(2).cwiseAbs().maxCoeff();
  const double q_peak = run.z.cols() > 3 ? run.z.rightCols(run.z.cols() - 3).cwiseAbs().maxCoeff() : 0.0;
  const double floor = 100.0 * options.integrator.atol;
  auto sizeable = [floor](double err, double peak) { return err > floor && err > 1e-2 * peak; };
  if (e.theta_rad > 1e-2 || sizeable(e.R_m, R_peak) || sizeable(e.q, q_peak)) {
    std::ostringstream w;
    w << std::setprecision(2) << what << ": not converged: the estimated global error reaches theta " << e.theta_rad
      << " rad, R " << e.R_m << " m (peak " << R_peak << "), q " << e.q << " (peak " << q_peak << ") near t = "
      << std::setprecision(4) << e.worst_time_s << " s; lower rtol (see README, [simulation])";
    r.warnings.push_back(w.str());
    if (study_log.warn) study_log.warn(w.str());
  }
  return e;
}

}  // namespace

SimulationStudyResult run_simulation_study(const Design& design, const ManeuverStudyResult* maneuver,
                                           const StudyLog& study_log) {
  const SimulationStudy& st = *design.simulation;
  const FlexibleBody body = design.body();
  Excitation ex = design.excitation();
  std::shared_ptr<const RigidTrajectory> nominal;
  if (maneuver && maneuver->flown) {
    // The optimized commands drive their actuators; the optimized motion is the nominal.
    ex = maneuver->flown->driving(ex);
    nominal = maneuver->flown->nominal();
  }
  const int n = body.n();
  std::ostream* log = study_log.log;
  SimulationStudyResult r;
  const double t_off = ex.end_time();
  r.loads_end_s = t_off;
  r.about_maneuver = static_cast<bool>(nominal);
  r.duration_s = st.options.duration_s;

  const FullModel full(body);
  if (st.nonlinear) {
    if (log) *log << "simulation: full nonlinear model, NOA " << n << ", " << st.options.duration_s << " s ... " << std::flush;
    ProgressReport progress(log, st.options.duration_s);
    SimulationOptions o = st.options;
    o.integrator.progress = progress.callback();
    SimulationStudyResult::Solution s;
    s.run = simulate_full(body, ex, o);
    const SimulationResult& nl = s.run;
    if (log) *log << progress.resume() << (nl.ok() ? "done" : "FAILED") << " (" << nl.steps << " steps, " << std::fixed << std::setprecision(3)
                  << nl.wall_time_s << " s)" << std::defaultfloat << '\n';
    if (nl.ok()) {
      s.table = response_table(body, nl, &full, s.header);
      const Eigen::MatrixXd& nl_table = s.table;
      const int ce = 1 + 2 * (3 + n) + 2;  // vibration_energy_J column (after t, z, z', two tips)
      s.residual_vibration_energy_J = nl_table(nl_table.rows() - 1, ce);
      // Invariants after the loads end, relative to their peaks; a momentum that stays
      // near zero is measured against the momentum the peak energy could carry.
      const ModalIntegrals& mi = body.integrals();
      const double E = nl_table.col(ce + 1).cwiseAbs().maxCoeff();
      const double P = std::max(nl_table.middleCols(ce + 2, 2).rowwise().norm().maxCoeff(), std::sqrt(2 * mi.m * E));
      const double H = std::max(nl_table.col(ce + 4).cwiseAbs().maxCoeff(), std::sqrt(2 * mi.I_o * E));
      s.drifts = Eigen::Vector3d(drift(nl_table, ce + 1, 1, t_off, E), drift(nl_table, ce + 2, 2, t_off, P),
                                 drift(nl_table, ce + 4, 1, t_off, H));
      if (st.error_estimate)
        s.error_estimate = estimate_error(
            "full nonlinear model", nl, st.options,
            [&](const SimulationOptions& tight) { return simulate_full(body, ex, tight); }, r, study_log);
    } else {
      fail(r, study_log, "full nonlinear simulation failed: " + nl.message);
    }
    r.nonlinear = std::move(s);
  }
  if (st.perturbation) {
    if (log) *log << "simulation: perturbation (zero-order, then first-order) ... " << std::flush;
    ProgressReport progress(log, st.options.duration_s);
    SimulationOptions o = st.options;
    o.integrator.progress = progress.callback();
    const PerturbationResult p =
        nominal ? simulate_perturbation_about(body, ex, nominal, o) : simulate_perturbation(body, ex, o);
    SimulationStudyResult::Solution s;
    s.run = p.total;
    s.zero_order_rhs_evaluations = p.zero_order.rhs_evaluations;
    s.first_order_rhs_evaluations = p.first_order_rhs_evaluations;
    const SimulationResult& pt = s.run;
    if (log) *log << progress.resume() << (pt.ok() ? "done" : "FAILED") << " (" << pt.steps << " steps, " << std::fixed << std::setprecision(3)
                  << pt.wall_time_s << " s)" << std::defaultfloat << '\n';
    if (pt.ok()) {
      s.table = response_table(body, pt, nullptr, s.header);
      s.residual_vibration_energy_J = s.table(s.table.rows() - 1, 1 + 2 * (3 + n) + 2);
      if (st.error_estimate)
        s.error_estimate = estimate_error(
            "perturbation solution", pt, st.options,
            [&](const SimulationOptions& tight) {
              return (nominal ? simulate_perturbation_about(body, ex, nominal, tight)
                              : simulate_perturbation(body, ex, tight)).total;
            },
            r, study_log);
    } else {
      fail(r, study_log, "perturbation simulation failed: " + pt.message);
    }
    r.perturbation = std::move(s);
  }
  if (r.nonlinear && r.perturbation && r.nonlinear->run.ok() && r.perturbation->run.ok()) {
    const Eigen::MatrixXd dz = (r.nonlinear->run.z - r.perturbation->run.z).cwiseAbs();
    SimulationStudyResult::Differences diff;
    diff.max_abs_dR_m = dz.leftCols(2).maxCoeff();
    diff.max_abs_dtheta_rad = dz.col(2).maxCoeff();
    diff.max_abs_dq = dz.rightCols(n).maxCoeff();
    diff.max_rigid_difference = dz.leftCols(3).maxCoeff();
    r.difference_nonlinear_minus_perturbation = diff;
    if (log)
      *log << "  max |full - perturbation|: R " << diff.max_abs_dR_m << " m, theta " << diff.max_abs_dtheta_rad
           << " rad, q " << diff.max_abs_dq << '\n';
  }
  return r;
}

namespace detail {

void write_simulation(const Design& design, const SimulationStudyResult& r, RunOutput& out) {
  const SimulationStudy& st = *design.simulation;
  const int n = design.noa;
  const bool nl_ok = r.nonlinear && r.nonlinear->run.ok(), pt_ok = r.perturbation && r.perturbation->run.ok();
  if (nl_ok) out.csv("nonlinear.csv", r.nonlinear->header, r.nonlinear->table);
  if (pt_ok) out.csv("perturbation.csv", r.perturbation->header, r.perturbation->table);

  // Figures in the manner of the paper's Figs. 4-7: both solutions overlaid.
  if (nl_ok || pt_ok) {
    const Eigen::MatrixXd& any = nl_ok ? r.nonlinear->run.z : r.perturbation->run.z;
    auto moves = [&](int c) {
      double m = any.col(c).cwiseAbs().maxCoeff();
      if (nl_ok && pt_ok) m = std::max(m, r.perturbation->run.z.col(c).cwiseAbs().maxCoeff());
      return m > 1e-9;
    };
    auto series = [&](int col, const std::string& what) {
      std::vector<PlotSeries> s;
      if (nl_ok) s.push_back({"nonlinear.csv", 1, col, what + " full nonlinear", "lines"});
      if (pt_ok) s.push_back({"perturbation.csv", 1, col, what + " perturbation", "lines dt 2"});
      return s;
    };
    PlotSpec rigid{st.rigid_figure, "Rigid-body motion: " + design.title, {}};
    const char* names[3] = {"R_x [m]", "R_y [m]", "theta [rad]"};
    for (int c = 0; c < 3; ++c)
      if (moves(c)) rigid.panels.push_back({names[c], "t [s]", names[c], series(2 + c, "")});
    if (rigid.panels.empty()) rigid.panels.push_back({names[1], "t [s]", names[1], series(3, "")});
    out.plot(rigid, design.plots);
    PlotSpec elastic{st.elastic_figure, "Generalized displacements: " + design.title, {}};
    for (int i = 0; i < n && elastic.panels.size() < 6; ++i)
      if (moves(3 + i)) {
        const std::string q = "q" + std::to_string(i + 1);
        elastic.panels.push_back({q, "t [s]", q, series(5 + i, "")});
      }
    if (!elastic.panels.empty()) out.plot(elastic, design.plots);

    // what an engineer checks first: the tips' deflection and the vibration energy
    // (columns of nonlinear.csv and perturbation.csv)
    PlotSpec vib{"vibration", "Tip deflection and vibration energy: " + design.title,
                 {{"tip deflection, left end", "t [s]", "w(left) [m]", {}},
                  {"tip deflection, right end", "t [s]", "w(right) [m]", {}},
                  {"vibration energy (log scale)", "t [s]", "E_vib [J]", {}, true}}};
    std::string energy_note;
    for (const auto* sol : {&r.nonlinear, &r.perturbation}) {
      if (!*sol || !(*sol)->run.ok()) continue;
      const std::vector<std::string>& header = (*sol)->header;
      const auto col = [&](const char* name) {
        return static_cast<int>(std::find(header.begin(), header.end(), name) - header.begin()) + 1;
      };
      const int tl = col("tip_left_m"), energy = col("vibration_energy_J");
      if (energy > static_cast<int>(header.size())) continue;
      const bool full = sol == &r.nonlinear;
      const std::string file = full ? "nonlinear.csv" : "perturbation.csv";
      const std::string label = full ? "full nonlinear" : "perturbation";
      const std::string style = full ? "lines" : "lines dt 2";
      vib.panels[0].series.push_back({file, 1, tl, label, style});
      vib.panels[1].series.push_back({file, 1, tl + 1, label, style});
      vib.panels[2].series.push_back({file, 1, energy, label, style});
      std::ostringstream note;
      note << (energy_note.empty() ? "; at the end: " : ", ") << label << " " << std::setprecision(3)
           << (*sol)->table(((*sol)->table.rows() - 1), energy - 1) << " J";
      energy_note += note.str();
    }
    vib.panels[2].title += energy_note;
    out.plot(vib, design.plots);
  }
}

namespace {
Json run_stats(const SimulationStudyResult::Solution& s) {
  const SimulationResult& r = s.run;
  Json j = Json::object();
  j["status"] = r.ok() ? "ok" : "failed";
  if (!r.ok()) j["message"] = r.message;
  j["rhs_evaluations"] = r.rhs_evaluations;
  j["steps"] = r.steps;
  j["wall_time_s"] = r.wall_time_s;
  if (const auto& e = s.error_estimate) {
    Json g = Json::object();
    g["method"] = "second run at rtol/10, atol/10; max difference over the output times";
    g["available"] = e->available;
    if (!e->available) g["message"] = e->message;
    g["rtol"] = e->rtol;
    g["atol"] = e->atol;
    if (e->available) {
      g["max_abs_R_m"] = e->R_m;
      g["max_abs_theta_rad"] = e->theta_rad;
      g["max_abs_q"] = e->q;
      g["max_abs_rates"] = e->rates;
      g["worst_time_s"] = e->worst_time_s;
    }
    g["rhs_evaluations"] = e->rhs_evaluations;
    g["wall_time_s"] = e->wall_time_s;
    j["global_error_estimate"] = g;
  }
  return j;
}
}  // namespace

Json to_json(const SimulationStudyResult& r) {
  Json js = Json::object();
  js["loads_end_s"] = r.loads_end_s;
  js["nominal"] = r.about_maneuver ? "optimized maneuver" : "zero-order simulation";
  js["duration_s"] = r.duration_s;
  if (r.nonlinear) {
    Json j = run_stats(*r.nonlinear);
    if (r.nonlinear->run.ok()) {
      j["residual_vibration_energy_J"] = r.nonlinear->residual_vibration_energy_J;
      j["energy_drift_rel"] = (*r.nonlinear->drifts)(0);
      j["linear_momentum_drift_rel"] = (*r.nonlinear->drifts)(1);
      j["angular_momentum_drift_rel"] = (*r.nonlinear->drifts)(2);
    }
    js["nonlinear"] = j;
  }
  if (r.perturbation) {
    Json j = run_stats(*r.perturbation);
    j["zero_order_rhs_evaluations"] = r.perturbation->zero_order_rhs_evaluations;
    j["first_order_rhs_evaluations"] = r.perturbation->first_order_rhs_evaluations;
    if (r.perturbation->run.ok()) j["residual_vibration_energy_J"] = r.perturbation->residual_vibration_energy_J;
    js["perturbation"] = j;
  }
  if (const auto& d = r.difference_nonlinear_minus_perturbation) {
    Json diff = Json::object();
    diff["max_abs_dR_m"] = d->max_abs_dR_m;
    diff["max_abs_dtheta_rad"] = d->max_abs_dtheta_rad;
    diff["max_abs_dq"] = d->max_abs_dq;
    diff["max_rigid_difference"] = d->max_rigid_difference;
    js["difference_nonlinear_minus_perturbation"] = diff;
  }
  return js;
}

}  // namespace detail
}  // namespace freeflex
