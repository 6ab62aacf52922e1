// Bang-bang switch-time design with NLopt SLSQP and Newton's method (see the header for
// the formulation): the closed-form stage, the first-order stage, and the options.
#include "freeflex/control/switch_time.hpp"

#include <nlopt.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <random>
#include <stdexcept>

#include "control/switch_time_model.hpp"

namespace freeflex {
namespace {

using namespace detail;
std::string fmt(double v) { return fmt10(v); }

/// The first problem of `o`, or "".
std::string options_problem(const SwitchTimeOptions& o) {
  if (!(o.rtol > 0.0) || !(o.atol > 0.0) || !(o.constraint_tolerance > 0.0) || o.starts < 1 || o.max_evaluations < 1 ||
      o.max_steps_per_simulation < 0)
    return "rtol, atol, constraint_tolerance must be > 0, starts, max_evaluations >= 1 and max_steps_per_simulation "
           ">= 0";
  return "";
}

/// Stage-1 modal constraints (closed form) and gradients (rows of 2 per mode).
void modal_closed_form(const Problem& P, const std::vector<double>& D, double* c, double* grad) {
  const int M = static_cast<int>(D.size());
  std::vector<double> t(M + 1, 0.0), jump(M + 1);
  for (int i = 1; i <= M; ++i) t[i] = t[i - 1] + D[i - 1];
  // torque jumps (units of τmax): +1 at 0, ∓2 at switches, ±1 at T (back to zero)
  jump[0] = 1.0;
  for (int i = 1; i < M; ++i) jump[i] = (i % 2 == 1) ? -2.0 : 2.0;
  // the last interval (index M-1) has sign + if (M-1) is even; the jump back to zero is −sign
  jump[M] = ((M - 1) % 2 == 0) ? -1.0 : 1.0;
  for (int j = 0; j < P.k; ++j) {
    const double w = P.modes.omega(j);
    const double amp = P.modes.participation(j) * P.tau / w / P.scale;
    std::complex<double> Z = 0.0;
    std::vector<std::complex<double>> dZdt(M + 1);
    for (int i = 0; i <= M; ++i) {
      const std::complex<double> e = std::polar(1.0, w * t[i]);
      Z += jump[i] * e;
      dZdt[i] = jump[i] * std::complex<double>(0.0, w) * e;
    }
    c[2 * j] = amp * Z.real();
    c[2 * j + 1] = amp * Z.imag();
    if (grad) {
      for (int l = 0; l < M; ++l) {  // t_i depends on D_l for l < i
        std::complex<double> g = 0.0;
        for (int i = l + 1; i <= M; ++i) g += dZdt[i];
        grad[(2 * j) * M + l] = amp * g.real();
        grad[(2 * j + 1) * M + l] = amp * g.imag();
      }
    }
  }
}

struct NloptData {
  Problem* P;
  bool closed_form;
  bool failed = false;
};

double objective(unsigned n, const double* x, double* grad, void*) {
  double T = 0.0;
  for (unsigned i = 0; i < n; ++i) {
    T += x[i];
    if (grad) grad[i] = 1.0;
  }
  return T;
}

/// Constraints: [θ0(T) − Δθ, θ0'(T)] (scaled by Δθ and a T*) then the modal ones.
void constraints(unsigned m, double* c, unsigned n, const double* x, double* grad, void* data) {
  auto* d = static_cast<NloptData*>(data);
  Problem& P = *d->P;
  const std::vector<double> D(x, x + n);
  double th = 0.0, rt = 0.0;
  std::vector<double> dth, drt;
  rigid_end(D, P.a, th, rt, grad ? &dth : nullptr, grad ? &drt : nullptr);
  const double rate_scale = P.scale / std::sqrt(P.I_o);  // θ'*
  c[0] = (th - P.dtheta) / P.dtheta;
  c[1] = rt / rate_scale;
  if (grad)
    for (unsigned l = 0; l < n; ++l) {
      grad[l] = dth[l] / P.dtheta;
      grad[n + l] = drt[l] / rate_scale;
    }
  if (m <= 2) return;
  if (d->closed_form) {
    modal_closed_form(P, D, c + 2, grad ? grad + 2 * n : nullptr);
    return;
  }
  Eigen::VectorXd x1;
  if (!simulate(P, D, x1)) {
    d->failed = true;
    for (unsigned i = 2; i < m; ++i) c[i] = 1.0;
    return;
  }
  modal_from_state(P, x1, c + 2);
  if (!grad) return;
  const double h = 1e-6 * (P.scale / std::sqrt(P.I_o) / P.a);  // 1e-6 T*/2
  std::vector<double> cp(m - 2), cm(m - 2);
  for (unsigned l = 0; l < n; ++l) {
    std::vector<double> Dp = D;
    // forward differences: one simulation per column; the truncation error h |c''| ~ 1e-5
    // and the noise (integration error / h ~ 1e-7) only slow Newton's convergence
    Dp[l] += h;
    Eigen::VectorXd xp;
    if (!simulate(P, Dp, xp)) {
      d->failed = true;
      return;
    }
    modal_from_state(P, xp, cp.data());
    for (unsigned i = 2; i < m; ++i) cm[i - 2] = c[i];
    const double den = h;
    for (unsigned i = 2; i < m; ++i) grad[i * n + l] = (cp[i - 2] - cm[i - 2]) / den;
  }
}

struct StageResult {
  bool feasible = false;
  std::vector<double> D;
  double T = 0.0, violation = 0.0;
};

StageResult run_slsqp(Problem& P, bool closed_form, const std::vector<double>& start, double tol, int max_eval) {
  const unsigned n = static_cast<unsigned>(start.size());
  const unsigned m = 2 + 2 * P.k;
  NloptData data{&P, closed_form};
  nlopt::opt opt(nlopt::LD_SLSQP, n);
  opt.set_min_objective(objective, nullptr);
  opt.add_equality_mconstraint(constraints, &data, std::vector<double>(m, 0.1 * tol));
  opt.set_lower_bounds(std::vector<double>(n, 0.0));
  const double Tstar = 2.0 * P.scale / std::sqrt(P.I_o) / P.a;
  opt.set_upper_bounds(std::vector<double>(n, 4.0 * Tstar));
  opt.set_xtol_rel(1e-10);
  opt.set_maxeval(max_eval);
  std::vector<double> x = start;
  double f = 0.0;
  try {
    opt.optimize(x, f);
  } catch (const std::exception&) {
    // roundoff-limited or forced stop: judge the point reached by its constraints
  }
  StageResult r;
  r.D = x;
  std::vector<double> c(m);
  NloptData check{&P, closed_form};
  constraints(m, c.data(), n, x.data(), nullptr, &check);
  for (double v : c) r.violation = std::max(r.violation, std::abs(v));
  r.feasible = !check.failed && !data.failed && r.violation <= tol;
  r.T = 0.0;
  for (double v : x) r.T += v;
  return r;
}

/// Stage 2: Newton's method on the square system (2k + 2 constraints, 2k + 2 durations)
/// with the central-difference Jacobian and a backtracking line search on ‖c‖, from the
/// closed-form design: it follows that design's root into the first-order model.
StageResult newton_first_order(Problem& P, const std::vector<double>& start, double tol, int max_iter) {
  const unsigned n = static_cast<unsigned>(start.size());
  const unsigned m = 2 + 2 * P.k;
  std::vector<double> D = start;
  std::vector<double> c(m), J(m * n);
  StageResult r;
  // merit: ½‖c‖² (the Newton direction descends it whenever the Jacobian is right)
  auto eval = [&](const std::vector<double>& x, std::vector<double>& cv, std::vector<double>* Jv, double& maxv) {
    NloptData data{&P, false};
    constraints(m, cv.data(), n, x.data(), Jv ? Jv->data() : nullptr, &data);
    double v = 0.0;
    maxv = 0.0;
    for (double e : cv) v += e * e, maxv = std::max(maxv, std::abs(e));
    return data.failed ? HUGE_VAL : v;
  };
  double viol = 0.0;
  double merit = eval(D, c, &J, viol);
  const double viol0 = viol;
  for (int it = 0; it < max_iter && viol > tol && std::isfinite(merit); ++it) {
    if (it >= 4 && viol > 1e-2 * viol0) break;  // not converging: not this root's basin
    const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Jm(J.data(), m, n);
    const Eigen::VectorXd step = Jm.colPivHouseholderQr().solve(-Eigen::Map<const Eigen::VectorXd>(c.data(), m));
    double alpha = 1.0;
    bool moved = false;
    for (int ls = 0; ls < 20; ++ls, alpha *= 0.5) {
      std::vector<double> Dn = D;
      for (unsigned l = 0; l < n; ++l) Dn[l] = std::max(0.0, D[l] + alpha * step(l));
      std::vector<double> cn(m);
      double vmax = 0.0;
      const double mn = eval(Dn, cn, nullptr, vmax);
      if (mn < (1.0 - 1e-4 * alpha) * merit) {
        D = Dn;
        moved = true;
        break;
      }
    }
    if (!moved) break;
    merit = eval(D, c, &J, viol);
  }
  r.D = D;
  r.violation = viol;
  r.feasible = viol <= tol;
  r.T = 0.0;
  for (double v : D) r.T += v;
  return r;
}

}  // namespace

void validate(const SwitchTimeOptions& o) {
  const std::string problem = options_problem(o);
  if (!problem.empty()) throw std::invalid_argument("switch-time options: " + problem);
}

SwitchTimeResult design_switch_times(const FlexibleBody& body, int actuator, double rotation_rad,
                                     double torque_limit_Nm, int modes, const SwitchTimeOptions& o) {
  const std::string where = "design_switch_times";
  validate_actuator(body, actuator, where);
  if (!(rotation_rad > 0.0) || !std::isfinite(rotation_rad))
    throw std::invalid_argument(where + ": rotation_rad = " + fmt(rotation_rad) + ", must be finite and > 0");
  if (!(torque_limit_Nm > 0.0) || !std::isfinite(torque_limit_Nm))
    throw std::invalid_argument(where + ": torque_limit_Nm = " + fmt(torque_limit_Nm) + ", must be finite and > 0");
  if (modes < 0 || modes > 4)
    throw std::invalid_argument(where + ": modes = " + std::to_string(modes) + ", must be in [0, 4]");
  const std::string problem = options_problem(o);
  if (!problem.empty()) throw std::invalid_argument(where + ": " + problem);
  const auto clock0 = std::chrono::steady_clock::now();

  Problem P;
  P.body = &body;
  P.actuator = actuator;
  P.k = modes;
  P.I_o = body.integrals().I_o;
  P.tau = torque_limit_Nm;
  P.a = P.tau / P.I_o;
  P.dtheta = rotation_rad;
  P.rtol = o.rtol;
  P.atol = o.atol;
  P.max_total_steps = o.max_steps_per_simulation;
  P.budget = o.budget;
  P.progress = o.progress;
  P.modes = target_modes(body, actuator, rotation_rad, modes, where);
  const double Tstar = 2.0 * std::sqrt(P.I_o * P.dtheta / P.tau);
  P.scale = std::sqrt(P.I_o) * P.a * Tstar / 2.0;  // sqrt(I_o) θ'* (rigid peak rate)

  SwitchTimeResult res;
  res.rigid_duration_s = Tstar;
  res.torque_limit_Nm = P.tau;
  res.mode_frequencies_rad_s = P.modes.omega;
  const int M = 2 * P.k + 2;

  // Stage 1: closed form, multi-start from antisymmetric patterns.
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  StageResult best;
  std::vector<StageResult> roots;  // distinct feasible closed-form designs
  for (int s = 0; s < (P.k == 0 ? 1 : o.starts); ++s) {
    const double h = 0.5 * Tstar * (1.0 + 0.6 * U(rng) * (P.k > 0));
    std::vector<double> sw(P.k);
    for (double& v : sw) v = h * U(rng);
    std::sort(sw.begin(), sw.end());
    std::vector<double> half;  // durations of the first half
    double prev = 0.0;
    for (double v : sw) half.push_back(v - prev), prev = v;
    half.push_back(h - prev);
    std::vector<double> D = half;
    D.insert(D.end(), half.rbegin(), half.rend());
    const StageResult r = run_slsqp(P, true, D, o.constraint_tolerance, o.max_evaluations);
    if (!r.feasible) continue;
    if (!best.feasible || r.T < best.T) best = r;
    bool seen = false;
    for (const auto& q : roots) {
      double dist = 0.0;
      for (std::size_t i = 0; i < q.D.size(); ++i) dist = std::max(dist, std::abs(q.D[i] - r.D[i]));
      seen = seen || dist < 1e-6 * Tstar;
    }
    if (!seen) roots.push_back(r);
  }
  std::sort(roots.begin(), roots.end(), [](const StageResult& a, const StageResult& b) { return a.T < b.T; });
  if (!best.feasible) {
    res.message = "closed-form stage found no feasible switch times in " + std::to_string(o.starts) + " starts";
    res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return res;
  }

  // Stage 2: the first-order model.
  // Stage 2 from the closed-form roots, shortest first, until one carries over.
  StageResult fin = best;
  if (P.k > 0) {
    for (std::size_t i = 0; i < roots.size() && i < 6; ++i) {
      fin = o.refine == SwitchTimeOptions::Refine::Newton
                ? newton_first_order(P, roots[i].D, o.constraint_tolerance, 12)
                : run_slsqp(P, false, roots[i].D, o.constraint_tolerance, o.max_evaluations);
      if (fin.feasible) {
        best = roots[i];
        break;
      }
    }
  }
  res.closed_form_switch_times = switches_of(best.D, res.closed_form_duration_s);
  res.simulations = P.simulations;
  if (P.k > 0) {
    Eigen::VectorXd x1c;
    if (simulate(P, best.D, x1c)) {
      std::vector<double> cc(2 * P.k);
      modal_from_state(P, x1c, cc.data());
      double e = 0.0;
      for (double v : cc) e += v * v;  // Σ E_j / E*, E* = ½ I_o θ'*² (the closed form's peak rate)
      res.closed_form_residual_ratio = e;
    }
  }
  res.switch_times = switches_of(fin.D, res.duration_s);
  Eigen::VectorXd x1;
  double peak = 0.0;
  if (!simulate(P, fin.D, x1, &peak)) {
    res.message = "first-order simulation of the design failed: " + P.last_error;
    res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return res;
  }
  rigid_end(fin.D, P.a, res.final_angle_rad, res.final_rate_rad_s, nullptr, nullptr);
  const int N = body.dofs();
  const Eigen::VectorXd eta = P.modes.shapes.transpose() * (P.modes.M0 * x1.head(N));
  const Eigen::VectorXd eta_d = P.modes.shapes.transpose() * (P.modes.M0 * x1.tail(N));
  res.residual_energy_J = 0.5 * (eta_d.cwiseAbs2() + P.modes.omega.cwiseAbs2().cwiseProduct(eta.cwiseAbs2()));
  res.peak_rate_rad_s = peak;
  res.rigid_kinetic_peak_J = 0.5 * P.I_o * peak * peak;
  res.residual_ratio = res.residual_energy_J.sum() / res.rigid_kinetic_peak_J;
  res.status = fin.feasible ? SwitchTimeResult::Status::Solved : SwitchTimeResult::Status::NotConverged;
  res.message = fin.feasible ? "solved"
                             : "the first-order stage did not meet the constraints: max violation " +
                                   fmt(fin.violation) + (P.last_error.empty() ? "" : " (" + P.last_error + ")");
  (void)M;
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
  return res;
}

}  // namespace freeflex
