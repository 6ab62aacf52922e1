// [simulation]: forced response with the full nonlinear model and the perturbation
// solution (zero-order then first-order), their differences, energies and momenta
// (the paper's Figs. 4-7).
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "freeflex/app/run.hpp"
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

Json run_stats(const SimulationResult& r) {
  Json j = Json::object();
  j["status"] = r.ok() ? "ok" : "failed";
  if (!r.ok()) j["message"] = r.message;
  j["rhs_evaluations"] = static_cast<double>(r.rhs_evaluations);
  j["steps"] = static_cast<double>(r.steps);
  j["wall_time_s"] = r.wall_time_s;
  return j;
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

}  // namespace

int run_simulation(const Design& design, RunOutput& out, Json& summary, const ManeuverOutcome* maneuver) {
  const SimulationStudy& st = *design.simulation;
  const FlexibleBody body(Beam(design.beam), design.noa, design.force_elements(), design.damping_ratios);
  Excitation ex = design.excitation();
  std::shared_ptr<const RigidTrajectory> nominal;
  if (maneuver && maneuver->trajectory) {
    // The optimized commands drive their actuators; the optimized motion is the nominal.
    maneuver->drive(ex);
    nominal = maneuver->nominal();
  }
  const int n = body.n();
  std::ostream* log = out.log();
  Json js = Json::object();
  const double t_off = ex.end_time();
  js["loads_end_s"] = t_off;
  js["nominal"] = nominal ? "optimized maneuver" : "zero-order simulation";
  js["duration_s"] = st.options.duration_s;
  int code = kExitOk;

  SimulationResult nl, pt;
  Eigen::MatrixXd nl_table, pt_table;
  std::vector<std::string> header;
  const FullModel full(body);
  if (st.nonlinear) {
    if (log) *log << "simulation: full nonlinear model, NOA " << n << ", " << st.options.duration_s << " s ... " << std::flush;
    ProgressReport progress(log, st.options.duration_s);
    SimulationOptions o = st.options;
    o.integrator.progress = progress.callback();
    nl = simulate_full(body, ex, o);
    if (log) *log << progress.resume() << (nl.ok() ? "done" : "FAILED") << " (" << nl.steps << " steps, " << std::fixed << std::setprecision(3)
                  << nl.wall_time_s << " s)" << std::defaultfloat << '\n';
    Json j = run_stats(nl);
    if (nl.ok()) {
      nl_table = response_table(body, nl, &full, header);
      out.csv("nonlinear.csv", header, nl_table);
      const int ce = 1 + 2 * (3 + n) + 2;  // vibration_energy_J column (after t, z, z', two tips)
      j["residual_vibration_energy_J"] = nl_table(nl_table.rows() - 1, ce);
      // Invariants after the loads end, relative to their peaks; a momentum that stays
      // near zero is measured against the momentum the peak energy could carry.
      const ModalIntegrals& mi = body.integrals();
      const double E = nl_table.col(ce + 1).cwiseAbs().maxCoeff();
      const double P = std::max(nl_table.middleCols(ce + 2, 2).rowwise().norm().maxCoeff(), std::sqrt(2 * mi.m * E));
      const double H = std::max(nl_table.col(ce + 4).cwiseAbs().maxCoeff(), std::sqrt(2 * mi.I_o * E));
      j["energy_drift_rel"] = drift(nl_table, ce + 1, 1, t_off, E);
      j["linear_momentum_drift_rel"] = drift(nl_table, ce + 2, 2, t_off, P);
      j["angular_momentum_drift_rel"] = drift(nl_table, ce + 4, 1, t_off, H);
    } else {
      code = kExitNumericalFailure;
      out.warn("full nonlinear simulation failed: " + nl.message);
    }
    js["nonlinear"] = j;
  }
  if (st.perturbation) {
    if (log) *log << "simulation: perturbation (zero-order, then first-order) ... " << std::flush;
    ProgressReport progress(log, st.options.duration_s);
    SimulationOptions o = st.options;
    o.integrator.progress = progress.callback();
    const PerturbationResult p =
        nominal ? simulate_perturbation_about(body, ex, nominal, o) : simulate_perturbation(body, ex, o);
    pt = p.total;
    if (log) *log << progress.resume() << (pt.ok() ? "done" : "FAILED") << " (" << pt.steps << " steps, " << std::fixed << std::setprecision(3)
                  << pt.wall_time_s << " s)" << std::defaultfloat << '\n';
    Json j = run_stats(pt);
    j["zero_order_rhs_evaluations"] = static_cast<double>(p.zero_order.rhs_evaluations);
    j["first_order_rhs_evaluations"] = static_cast<double>(p.first_order_rhs_evaluations);
    if (pt.ok()) {
      pt_table = response_table(body, pt, nullptr, header);
      out.csv("perturbation.csv", header, pt_table);
      j["residual_vibration_energy_J"] = pt_table(pt_table.rows() - 1, 1 + 2 * (3 + n) + 2);
    } else {
      code = kExitNumericalFailure;
      out.warn("perturbation simulation failed: " + pt.message);
    }
    js["perturbation"] = j;
  }
  const bool both = nl.ok() && pt.ok() && st.nonlinear && st.perturbation;
  if (both) {
    const Eigen::MatrixXd dz = (nl.z - pt.z).cwiseAbs();
    Json diff = Json::object();
    diff["max_abs_dR_m"] = dz.leftCols(2).maxCoeff();
    diff["max_abs_dtheta_rad"] = dz.col(2).maxCoeff();
    diff["max_abs_dq"] = dz.rightCols(n).maxCoeff();
    diff["max_rigid_difference"] = dz.leftCols(3).maxCoeff();
    js["difference_nonlinear_minus_perturbation"] = diff;
    if (log)
      *log << "  max |full - perturbation|: R " << dz.leftCols(2).maxCoeff() << " m, theta " << dz.col(2).maxCoeff()
           << " rad, q " << dz.rightCols(n).maxCoeff() << '\n';
  }

  // Figures in the manner of the paper's Figs. 4-7: both solutions overlaid.
  if (nl.ok() || pt.ok()) {
    const Eigen::MatrixXd& any = nl.ok() ? nl.z : pt.z;
    auto moves = [&](int c) {
      double m = any.col(c).cwiseAbs().maxCoeff();
      if (nl.ok() && pt.ok()) m = std::max(m, pt.z.col(c).cwiseAbs().maxCoeff());
      return m > 1e-9;
    };
    auto series = [&](int col, const std::string& what) {
      std::vector<PlotSeries> s;
      if (nl.ok()) s.push_back({"nonlinear.csv", 1, col, what + " full nonlinear", "lines"});
      if (pt.ok()) s.push_back({"perturbation.csv", 1, col, what + " perturbation", "lines dt 2"});
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
  }
  summary["simulation"] = js;
  return code;
}

}  // namespace freeflex
