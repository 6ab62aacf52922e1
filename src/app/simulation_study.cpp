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
#include "util/format.hpp"
#include "freeflex/app/progress.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "freeflex/io/plot.hpp"
#include "freeflex/sim/prescribed.hpp"
#include "freeflex/sim/simulate.hpp"

#include <Eigen/Eigenvalues>

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
void fail(SimulationStudyResult& r, const StudyLog& study_log, const std::string& why,
          StudyStatus status = StudyStatus::Failed) {
  r.status = r.status == StudyStatus::Failed ? r.status : status;
  r.message = r.message.empty() ? why : r.message + "; " + why;
  r.warnings.push_back(why);
  if (study_log.warn) study_log.warn(why);
}

/// Why a run that spent the study's work budget may have: the explicit pairs in modal
/// variables below atol 1e-13 take steps the derivatives' round-off sets (docs/theory.md
/// section 8), hundreds of times more than needed. Empty when that is not the case.
std::string budget_hint(const SimulationOptions& o, SimulationOptions::Variables variables) {
  using M = IntegratorOptions::Method;
  const bool pair = o.integrator.method == M::Dop853 || o.integrator.method == M::Verner98;
  if (!pair || variables != SimulationOptions::Variables::Modal || !(o.integrator.atol < 1e-13) ||
      !o.integrator.budget || !o.integrator.budget->exhausted())
    return {};
  return " (this run had atol " + util::format_number(o.integrator.atol, 3) +
         ": with method \"dop853\" or \"verner98\" in modal variables an atol below 1e-13 lets the derivatives' "
         "round-off, not the accuracy, set the steps; keep [simulation] atol at 1e-12 or above, where the error "
         "estimate's second run has 1e-13, or integrate in physical variables)";
}

void warn(SimulationStudyResult& r, const StudyLog& study_log, const std::string& w) {
  r.warnings.push_back(w);
  if (study_log.warn) study_log.warn(w);
}

/// The lowest elastic frequency with the reference frame held: sqrt of the smallest
/// eigenvalue of (K, M). Spin at Ω softens the paper's model by Ω² M (eq. 14.12), which
/// cancels this mode's stiffness at Ω = ω1: the scale the spin rate is measured against.
double held_first_frequency(const FlexibleBody& body) {
  const ModalIntegrals& mi = body.integrals();
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(mi.K, mi.M, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, es.eigenvalues()(0)));
}

/// A spin rate at this fraction of the held first frequency or more, in a model without
/// geometric stiffening, draws a warning: its centrifugal softening (Ω/ω1)² of the first
/// mode's stiffness is then 9 % or more, against a stiffening the model leaves out.
constexpr double kSpinWarningRatio = 0.3;
/// A deflection beyond this fraction of the length draws a warning (the shortening is kept
/// to second order only); the run ends out of range at SimulationOptions::max_deflection_ratio.
constexpr double kDeflectionWarningRatio = 0.1;
/// An energy balance off by more than this (relative) draws a warning.
constexpr double kEnergyBalanceWarning = 1e-4;

/// The range figures of a run and their warnings (`what` names the run in them).
void assess_range(SimulationStudyResult& r, const StudyLog& study_log, const FlexibleBody& body,
                  SimulationStudyResult::Solution& s, const FullModel* full, const std::string& what) {
  const SimulationResult& run = s.run;
  auto& g = s.range;
  s.geometric_stiffening = body.geometric_stiffening();
  g.length_m = body.beam().length();
  g.first_frequency_rad_s = held_first_frequency(body);
  const int n = body.n(), T = static_cast<int>(run.t.size());
  if (T == 0) return;
  // The spin rate: the prescribed θ', or for a free body the rate of its angular momentum
  // about o over its inertia about o, θ' + Φ̃ q' / (I_o + qᵀ M q), which leaves out the
  // wobble of a frame tied to the slope at o (eq. 6.7).
  const ModalIntegrals& mi = body.integrals();
  for (int i = 0; i < T; ++i) {
    double w = run.z_dot(i, 2);
    if (!r.prescribed_motion) {
      const Eigen::VectorXd q = run.z.row(i).tail(n).transpose();
      w += mi.Phi_tilde.dot(run.z_dot.row(i).tail(n)) / (mi.I_o + q.dot(mi.M * q));
    }
    g.peak_spin_rate_rad_s = std::max(g.peak_spin_rate_rad_s, std::abs(w));
  }
  g.spin_ratio = g.first_frequency_rad_s > 0.0 ? g.peak_spin_rate_rad_s / g.first_frequency_rad_s : 0.0;
  const Eigen::MatrixXd P = deflection_sampler(body);
  g.peak_deflection_m = (run.z.rightCols(n) * P.transpose()).cwiseAbs().maxCoeff();
  g.deflection_ratio = g.peak_deflection_m / g.length_m;
  if (full && run.work_J.size() == T) {
    const int N = body.dofs();
    Eigen::VectorXd x(2 * N);
    x << run.z.row(0).transpose(), run.z_dot.row(0).transpose();
    const double e0 = full->energy(x);
    double worst = 0.0, scale = 0.0, de = 0.0;
    for (int i = 0; i < T; ++i) {
      x << run.z.row(i).transpose(), run.z_dot.row(i).transpose();
      de = full->energy(x) - e0;
      worst = std::max(worst, std::abs(de - run.work_J(i)));
      scale = std::max({scale, std::abs(de), std::abs(run.work_J(i))});
    }
    g.energy_change_J = de;
    g.work_J = run.work_J(T - 1);
    g.energy_balance_error_rel = scale > 0.0 ? worst / scale : 0.0;
    if (*g.energy_balance_error_rel > kEnergyBalanceWarning)
      warn(r, study_log, what + ": the energy balance is off by " + util::format_number(*g.energy_balance_error_rel, 3) +
                             " of the work done (energy change " + util::format_number(de, 6) + " J, work " +
                             util::format_number(*g.work_J, 6) + " J): tighten rtol/atol");
  }
  if (!body.geometric_stiffening() && g.spin_ratio >= kSpinWarningRatio)
    warn(r, study_log, what + ": the spin rate reaches " + util::format_number(g.peak_spin_rate_rad_s, 4) + " rad/s, " +
                           util::format_number(g.spin_ratio, 3) + " of the first elastic frequency (" +
                           util::format_number(g.first_frequency_rad_s, 4) +
                           " rad/s with the reference held), in a model without geometric stiffening: it softens "
                           "the beam by (spin/frequency)^2 and diverges past 1; set [model] geometric_stiffening = true");
  if (g.deflection_ratio > kDeflectionWarningRatio && g.deflection_ratio <= 1.0)
    warn(r, study_log, what + ": the elastic deflection reaches " + util::format_number(g.deflection_ratio, 3) +
                           " of the beam's length; the model keeps the shortening of the bent beam to second order "
                           "only (small deflections)");
}

/// Records a run's outcome: its table (also up to the time a run left its range) or its failure.
/// `full`: the invariants' columns (a free body); `energy`: the energy balance (full model).
void settle(SimulationStudyResult& r, const StudyLog& study_log, const FlexibleBody& body,
            SimulationStudyResult::Solution& s, const FullModel* full, const FullModel* energy, const std::string& what) {
  const SimulationResult& run = s.run;
  s.geometric_stiffening = body.geometric_stiffening();
  if (run.ok() || run.status == IntegrationStatus::OutOfRange) {
    s.table = response_table(body, run, full, s.header);
    assess_range(r, study_log, body, s, energy, what);
  }
  if (run.status == IntegrationStatus::OutOfRange)
    fail(r, study_log, what + " left its range: " + run.message, StudyStatus::OutOfRange);
}

/// The second run of the error estimate, its line in the log and, when the estimate is a
/// sizeable part of the motion, a warning that the result is not converged.
template <class Simulate>
GlobalErrorEstimate estimate_error(const char* what, const SimulationResult& run, const SimulationOptions& options,
                                   SimulationOptions::Variables variables, Simulate simulate, SimulationStudyResult& r,
                                   const StudyLog& study_log) {
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
    const std::string w = std::string(what) + ": no global error estimate: " + e.message + budget_hint(tight, variables);
    const auto& budget = options.integrator.budget;
    if (budget && budget->exhausted())
      fail(r, study_log, w);  // the study's work budget ran out in the second run: the study ends there
    else {
      r.warnings.push_back(w);
      if (study_log.warn) study_log.warn(w);
    }
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
  // every run of the study, error estimates included, is charged to one work budget
  SimulationOptions options = st.options;
  options.integrator.budget = std::make_shared<WorkBudget>(design.study_work, "the [simulation] study");
  const WorkBudget& budget = *options.integrator.budget;
  std::vector<std::string> not_run;  // runs left out once the budget is spent
  auto can_run = [&](const std::string& what) {
    if (budget.exhausted()) not_run.push_back(what);
    return !budget.exhausted();
  };
  const FlexibleBody body = design.body();
  Excitation ex = design.excitation();
  std::optional<PrescribedMotion> motion;
  if (design.motion) motion = design.motion->trajectory();
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
  r.duration_s = options.duration_s;
  r.first_order_solver = options.first_order_solver;
  r.prescribed_motion = static_cast<bool>(motion);
  r.method = options.integrator.method;
  r.full_variables = motion ? SimulationOptions::Variables::Physical : options.full_variables;
  // a prescribed motion integrates q in physical coordinates, whatever the options say
  r.first_order_variables = motion ? SimulationOptions::Variables::Physical : options.first_order_variables;

  const FullModel full(body);
  if (st.nonlinear) {
    if (log)
      *log << "simulation: full nonlinear model, NOA " << n << ", " << options.duration_s << " s"
           << (r.full_variables == SimulationOptions::Variables::Physical
                   ? ""
                   : std::string(", ") + to_string(r.full_variables) + " variables")
           << " ... " << std::flush;
    ProgressReport progress(log, options.duration_s);
    SimulationOptions o = options;
    o.integrator.progress = progress.callback();
    o.energy_balance = true;  // the range report's energy balance (full model)
    SimulationStudyResult::Solution s;
    s.run = motion ? simulate_prescribed(body, ex, *motion, o, false) : simulate_full(body, ex, o);
    const SimulationResult& nl = s.run;
    if (log) *log << progress.resume() << (nl.ok() ? "done" : nl.status == IntegrationStatus::OutOfRange ? "OUT OF RANGE" : "FAILED") << " (" << nl.steps << " steps, " << std::fixed << std::setprecision(3)
                  << nl.wall_time_s << " s)" << std::defaultfloat << '\n';
    settle(r, study_log, body, s, motion ? nullptr : &full, &full, "full nonlinear model");
    if (nl.ok() && !motion) {
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
    } else if (nl.status == IntegrationStatus::Failed) {
      fail(r, study_log, "full nonlinear simulation failed: " + nl.message + budget_hint(options, r.full_variables));
    } else if (nl.ok()) {
      s.residual_vibration_energy_J = s.table(s.table.rows() - 1, 1 + 2 * (3 + n) + 2);
    }
    if (nl.ok() && st.error_estimate && can_run("the full nonlinear model's error estimate"))
      s.error_estimate = estimate_error(
          "full nonlinear model", nl, options, r.full_variables,
          [&](const SimulationOptions& tight) {
            return motion ? simulate_prescribed(body, ex, *motion, tight, false) : simulate_full(body, ex, tight);
          },
          r, study_log);
    r.nonlinear = std::move(s);
  }
  if (st.compare_stiffening && can_run("the comparison without / with geometric stiffening")) {
    const FlexibleBody other(Beam(design.beam), design.noa, design.basis, design.force_elements(),
                             design.damping_ratios, !design.geometric_stiffening);
    const FullModel other_full(other);
    const std::string what = std::string("full nonlinear model ") +
                             (other.geometric_stiffening() ? "with" : "without") + " geometric stiffening (comparison)";
    if (log) *log << "simulation: " << what << " ... " << std::flush;
    ProgressReport progress(log, options.duration_s);
    SimulationOptions o = options;
    o.integrator.progress = progress.callback();
    o.energy_balance = true;  // the range report's energy balance (full model)
    SimulationStudyResult::Solution s;
    s.run = motion ? simulate_prescribed(other, ex, *motion, o, false) : simulate_full(other, ex, o);
    if (log) *log << progress.resume() << to_string(s.run.status) << " (" << s.run.steps << " steps)\n";
    // the comparison's own range does not change the study's status: it is reported in its entry
    if (s.run.ok() || s.run.status == IntegrationStatus::OutOfRange) {
      s.table = response_table(other, s.run, motion ? nullptr : &other_full, s.header);
      assess_range(r, study_log, other, s, &other_full, what);
    }
    if (s.run.status == IntegrationStatus::OutOfRange)
      warn(r, study_log, what + " left its range: " + s.run.message);
    else if (!s.run.ok() && budget.exhausted())
      fail(r, study_log, what + " failed: " + s.run.message);  // the study's work budget ran out in it
    else if (!s.run.ok())
      warn(r, study_log, what + " failed: " + s.run.message);
    if (s.run.ok() && st.error_estimate && can_run("the comparison's error estimate"))
      s.error_estimate = estimate_error(
          what.c_str(), s.run, options, options.full_variables,
          [&](const SimulationOptions& tight) {
            return motion ? simulate_prescribed(other, ex, *motion, tight, false) : simulate_full(other, ex, tight);
          },
          r, study_log);
    r.comparison = std::move(s);
  }
  if (st.perturbation && can_run("the perturbation solution")) {
    if (log) *log << "simulation: perturbation (zero-order, then first-order) ... " << std::flush;
    ProgressReport progress(log, options.duration_s);
    SimulationOptions o = options;
    o.integrator.progress = progress.callback();
    o.energy_balance = true;  // the range report's energy balance (full model)
    SimulationStudyResult::Solution s;
    if (motion) {
      s.run = simulate_prescribed(body, ex, *motion, o, true);
      s.zero_order_rhs_evaluations = 0;
      s.first_order_rhs_evaluations = s.run.rhs_evaluations;
    } else {
      const PerturbationResult p =
          nominal ? simulate_perturbation_about(body, ex, nominal, o) : simulate_perturbation(body, ex, o);
      s.run = p.total;
      s.zero_order_rhs_evaluations = p.zero_order.rhs_evaluations;
      s.first_order_rhs_evaluations = p.first_order_rhs_evaluations;
    }
    const SimulationResult& pt = s.run;
    if (log) *log << progress.resume() << (pt.ok() ? "done" : "FAILED") << " (" << pt.steps << " steps, " << std::fixed << std::setprecision(3)
                  << pt.wall_time_s << " s)" << std::defaultfloat << '\n';
    settle(r, study_log, body, s, nullptr, nullptr, "perturbation solution");
    if (pt.ok()) {
      s.residual_vibration_energy_J = s.table(s.table.rows() - 1, 1 + 2 * (3 + n) + 2);
      if (st.error_estimate && can_run("the perturbation solution's error estimate"))
        s.error_estimate = estimate_error(
            "perturbation solution", pt, options, r.first_order_variables,
            [&](const SimulationOptions& tight) {
              if (motion) return simulate_prescribed(body, ex, *motion, tight, true);
              return (nominal ? simulate_perturbation_about(body, ex, nominal, tight)
                              : simulate_perturbation(body, ex, tight)).total;
            },
            r, study_log);
    } else if (pt.status == IntegrationStatus::Failed) {
      fail(r, study_log,
           "perturbation simulation failed: " + pt.message + budget_hint(options, r.first_order_variables));
    }
    r.perturbation = std::move(s);
  }
  if (!not_run.empty()) {
    std::string list;
    for (const auto& w : not_run) list += (list.empty() ? "" : ", ") + w;
    fail(r, study_log, budget.spent_message() + ": not run: " + list);
  }
  r.work_units = budget.spent();
  r.work_budget_units = budget.total();
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
namespace {

/// An end whose deflection peaks below this fraction of the other end's is not drawn in
/// vibration.png (it is a clamped root: its ±1e-19 is round-off).
constexpr double kNegligibleEnd = 1e-12;

/// "" for a run that completed; for one that stopped, "stopped at T s: out of range", T
/// the last time it reached.
std::string stopped_note(const SimulationStudyResult::Solution& s) {
  if (s.run.ok()) return "";
  std::ostringstream os;
  os << "stopped at " << std::setprecision(4) << (s.table.rows() ? s.table(s.table.rows() - 1, 0) : 0.0) << " s: "
     << (s.run.status == IntegrationStatus::OutOfRange ? "out of range" : "failed");
  return os.str();
}

/// `title` of a series of run `s`, with the stopped note of a run that stopped:
/// "full nonlinear (stopped at ...)", "full nonlinear (no stiffening; stopped at ...)".
std::string run_title(const SimulationStudyResult::Solution& s, const std::string& title) {
  const std::string note = stopped_note(s);
  if (note.empty()) return title;
  if (!title.empty() && title.back() == ')') return title.substr(0, title.size() - 1) + "; " + note + ")";
  return title + " (" + note + ")";
}

/// A series of run `s` in a figure: a run that stopped is named so and does not set the
/// y range when a completed run is beside it (its last values may be far off).
PlotSeries run_series(const SimulationStudyResult::Solution& s, const std::string& file, int column,
                      const std::string& title, const std::string& style) {
  PlotSeries p{file, 1, column, run_title(s, title), style};
  p.sets_range = s.run.ok();
  return p;
}

}  // namespace

void write_simulation(const Design& design, const SimulationStudyResult& r, RunOutput& out) {
  const SimulationStudy& st = *design.simulation;
  const int n = design.noa;
  // a run that left its range keeps its table up to that time
  const bool nl_ok = r.nonlinear && r.nonlinear->table.size(), pt_ok = r.perturbation && r.perturbation->table.size();
  if (nl_ok) out.csv("nonlinear.csv", r.nonlinear->header, r.nonlinear->table);
  if (pt_ok) out.csv("perturbation.csv", r.perturbation->header, r.perturbation->table);
  const std::string cmp_csv = std::string("nonlinear_stiffening_") + (design.geometric_stiffening ? "off" : "on") + ".csv";
  const bool cmp_ok = r.comparison && r.comparison->table.size();
  if (cmp_ok) out.csv(cmp_csv, r.comparison->header, r.comparison->table);
  if (st.compare_stiffening && (nl_ok || cmp_ok)) {
    // the tip deflections of every run (columns tip_left_m, tip_right_m after t, z, z')
    const int c_left = 2 + 2 * (3 + n), c_right = c_left + 1;
    const std::string own = design.geometric_stiffening ? " (stiffening)" : " (no stiffening)";
    const std::string other = design.geometric_stiffening ? " (no stiffening)" : " (stiffening)";
    PlotSpec tips{st.tip_figure, "Tip deflection in the body frame: " + design.title, {}};
    const double x_left = Beam(design.beam).x_left();
    for (int c : {c_left, c_right}) {
      if (c == c_left && x_left == 0.0) continue;  // o at the left end: that tip is clamped
      const std::string side = c == c_left ? "left tip [m]" : "right tip [m]";
      std::vector<PlotSeries> series;
      if (nl_ok) series.push_back(run_series(*r.nonlinear, "nonlinear.csv", c, "full nonlinear" + own, "lines"));
      if (cmp_ok) series.push_back(run_series(*r.comparison, cmp_csv, c, "full nonlinear" + other, "lines dt 2"));
      if (pt_ok) series.push_back(run_series(*r.perturbation, "perturbation.csv", c, "first order" + own, "lines dt 3"));
      tips.panels.push_back({side, "t [s]", side, series});
    }
    out.plot(tips, design.plots);
  }

  // Figures in the manner of the paper's Figs. 4-7: both solutions overlaid.
  if (nl_ok || pt_ok) {
    const Eigen::MatrixXd& any = nl_ok ? r.nonlinear->run.z : r.perturbation->run.z;
    auto moves = [&](int c) {  // in either run
      return detail::moves(any.col(c)) || (nl_ok && pt_ok && detail::moves(r.perturbation->run.z.col(c)));
    };
    auto series = [&](int col, const std::string& what) {
      std::vector<PlotSeries> s;
      if (nl_ok) s.push_back(run_series(*r.nonlinear, "nonlinear.csv", col, what + " full nonlinear", "lines"));
      if (pt_ok) s.push_back(run_series(*r.perturbation, "perturbation.csv", col, what + " perturbation", "lines dt 2"));
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
    double peak_left = 0.0, peak_right = 0.0;  // of the runs drawn
    for (const auto* sol : {&r.nonlinear, &r.perturbation}) {
      if (!*sol || !(*sol)->table.size()) continue;  // a run that stopped: what it computed, named so
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
      vib.panels[0].series.push_back(run_series(**sol, file, tl, label, style));
      vib.panels[1].series.push_back(run_series(**sol, file, tl + 1, label, style));
      vib.panels[2].series.push_back(run_series(**sol, file, energy, label, style));
      peak_left = std::max(peak_left, (*sol)->table.col(tl - 1).cwiseAbs().maxCoeff());
      peak_right = std::max(peak_right, (*sol)->table.col(tl).cwiseAbs().maxCoeff());
      if (!(*sol)->run.ok()) continue;  // no end to tell: its key says where it stopped
      std::ostringstream note;
      note << (energy_note.empty() ? "; at the end: " : ", ") << label << " " << std::setprecision(3)
           << (*sol)->table(((*sol)->table.rows() - 1), energy - 1) << " J";
      energy_note += note.str();
    }
    vib.panels[2].title += energy_note;
    // an end that does not deflect (clamped at o: a cantilever's root) would be a panel of
    // round-off: left out when its deflection is negligible beside the other end's
    if (peak_left < kNegligibleEnd * peak_right)
      vib.panels.erase(vib.panels.begin());
    else if (peak_right < kNegligibleEnd * peak_left)
      vib.panels.erase(vib.panels.begin() + 1);
    out.plot(vib, design.plots);
  }
}

namespace {
Json run_stats(const SimulationStudyResult::Solution& s) {
  const SimulationResult& r = s.run;
  Json j = Json::object();
  j["status"] = r.ok() ? "ok" : to_string(r.status);
  if (!r.ok()) j["message"] = r.message;
  j["geometric_stiffening"] = s.geometric_stiffening;
  j["rhs_evaluations"] = r.rhs_evaluations;
  j["steps"] = r.steps;
  j["wall_time_s"] = r.wall_time_s;
  if (s.table.size()) {
    const auto& g = s.range;
    Json range = Json::object();
    range["peak_spin_rate_rad_s"] = g.peak_spin_rate_rad_s;
    range["first_elastic_frequency_rad_s"] = g.first_frequency_rad_s;
    range["spin_ratio"] = g.spin_ratio;
    range["peak_deflection_m"] = g.peak_deflection_m;
    range["length_m"] = g.length_m;
    range["deflection_ratio"] = g.deflection_ratio;
    if (g.energy_balance_error_rel) {
      range["energy_change_J"] = *g.energy_change_J;
      range["work_J"] = *g.work_J;
      range["energy_balance_error_rel"] = *g.energy_balance_error_rel;
    }
    j["range"] = range;
  }
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
  js["work_units"] = r.work_units;  // of the study's budget (README, the "(limits)" row)
  js["work_budget_units"] = r.work_budget_units;
  js["nominal"] = r.about_maneuver ? "optimized maneuver" : "zero-order simulation";
  js["duration_s"] = r.duration_s;
  js["prescribed_motion"] = r.prescribed_motion;
  js["method"] = to_string(r.method);
  if (r.nonlinear) {
    Json j = run_stats(*r.nonlinear);
    j["variables"] = to_string(r.full_variables);
    if (r.nonlinear->run.ok() && r.nonlinear->drifts) {
      j["residual_vibration_energy_J"] = r.nonlinear->residual_vibration_energy_J;
      j["energy_drift_rel"] = (*r.nonlinear->drifts)(0);
      j["linear_momentum_drift_rel"] = (*r.nonlinear->drifts)(1);
      j["angular_momentum_drift_rel"] = (*r.nonlinear->drifts)(2);
    }
    js["nonlinear"] = j;
  }
  if (r.comparison)
    js[r.comparison->geometric_stiffening ? "nonlinear_stiffening_on" : "nonlinear_stiffening_off"] =
        run_stats(*r.comparison);
  if (r.perturbation) {
    Json j = run_stats(*r.perturbation);
    j["first_order_solver"] = to_string(r.first_order_solver);
    if (r.first_order_solver == SimulationOptions::FirstOrderSolver::Integrator)
      j["first_order_variables"] = to_string(r.first_order_variables);
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
