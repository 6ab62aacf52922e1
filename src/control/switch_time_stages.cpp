// The switch-time design's solvers (control/switch_time_stages.hpp): the constraints in
// the closed form and in the first-order model, SLSQP, Newton's method, and the
// continuation in the rotation's size that carries a closed-form root into the model.
#include "control/switch_time_stages.hpp"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <complex>

namespace freeflex::detail {
namespace {

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
  if (d->closed_form) ++P.closed_form_evaluations;
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
  // forward differences: one simulation per column; the truncation error h |c''| ~ 1e-5
  // and the noise (integration error / h ~ 1e-7) only slow Newton's convergence
  const double h = 1e-6 * (P.scale / std::sqrt(P.I_o) / P.a);  // 1e-6 T*/2
  std::vector<double> cp(m - 2);
  for (unsigned l = 0; l < n; ++l) {
    std::vector<double> Dp = D;
    Dp[l] += h;
    Eigen::VectorXd xp;
    if (!simulate(P, Dp, xp)) {
      d->failed = true;
      return;
    }
    modal_from_state(P, xp, cp.data());
    for (unsigned i = 2; i < m; ++i) grad[i * n + l] = (cp[i - 2] - c[i]) / h;
  }
}

/// The scaled constraints at D (and their Jacobian, row-major, when J is given); the
/// largest |c|, or HUGE_VAL when a simulation failed.
double evaluate(Problem& P, bool closed_form, const std::vector<double>& D, std::vector<double>& c,
                std::vector<double>* J) {
  const unsigned n = static_cast<unsigned>(D.size()), m = 2 + 2 * P.k;
  c.assign(m, 0.0);
  if (J) J->assign(m * n, 0.0);
  NloptData data{&P, closed_form};
  constraints(m, c.data(), n, D.data(), J ? J->data() : nullptr, &data);
  if (data.failed) return HUGE_VAL;
  double v = 0.0;
  for (double e : c) v = std::max(v, std::abs(e));
  return v;
}

StageResult finish(std::vector<double> D, double violation, double tol) {
  StageResult r;
  r.D = std::move(D);
  r.violation = violation;
  r.feasible = violation <= tol;
  for (double v : r.D) r.T += v;
  return r;
}

/// Newton's method on the square system (2k + 2 constraints, 2k + 2 durations) with the
/// forward-difference Jacobian and a backtracking line search on ‖c‖: it follows the
/// root whose basin `start` lies in, or gives up.
StageResult newton_first_order(Problem& P, const std::vector<double>& start, double tol) {
  const int n = static_cast<int>(start.size()), m = 2 + 2 * P.k;
  std::vector<double> D = start, c, J;
  double viol = evaluate(P, false, D, c, &J);
  const double viol0 = viol;
  auto merit = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double e : v) s += e * e;
    return s;
  };
  for (int it = 0; it < kNewtonIterations && viol > tol && std::isfinite(viol); ++it) {
    if (it >= 4 && viol > 1e-2 * viol0) break;  // not converging: not this root's basin
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const Eigen::Map<const RowMajor> Jm(J.data(), m, n);
    const Eigen::VectorXd step = Jm.colPivHouseholderQr().solve(-Eigen::Map<const Eigen::VectorXd>(c.data(), m));
    const double f0 = merit(c);
    bool moved = false;
    double alpha = 1.0;
    for (int ls = 0; ls < kLineSearchTrials && !P.budget_spent; ++ls, alpha *= 0.5) {
      std::vector<double> Dn = D, cn;
      for (int l = 0; l < n; ++l) Dn[l] = std::max(0.0, D[l] + alpha * step(l));
      const double vn = evaluate(P, false, Dn, cn, nullptr);
      if (std::isfinite(vn) && merit(cn) < (1.0 - 1e-4 * alpha) * f0) {
        D = Dn, c = cn, viol = vn;
        moved = true;
        break;
      }
    }
    if (!moved) break;
    if (viol > tol && it + 1 < kNewtonIterations) viol = evaluate(P, false, D, c, &J);  // the next Jacobian
  }
  return finish(D, viol, tol);
}

/// Sets the problem to the rotation λ Δθ at λ τmax (same T*) for its lifetime.
class Resized {
 public:
  Resized(Problem& P, double lambda) : P_(P), tau_(P.tau), a_(P.a), dtheta_(P.dtheta), scale_(P.scale) {
    P.tau *= lambda, P.a *= lambda, P.dtheta *= lambda, P.scale *= lambda;
  }
  ~Resized() { P_.tau = tau_, P_.a = a_, P_.dtheta = dtheta_, P_.scale = scale_; }
  Resized(const Resized&) = delete;
  Resized& operator=(const Resized&) = delete;

 private:
  Problem& P_;
  double tau_, a_, dtheta_, scale_;
};

}  // namespace

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
  std::vector<double> c;
  const double viol = data.failed ? HUGE_VAL : evaluate(P, closed_form, x, c, nullptr);
  return finish(x, viol, tol);
}

StageResult continue_to_first_order(Problem& P, const std::vector<double>& root, double tol, bool slsqp,
                                    int max_eval) {
  const std::size_t n = root.size();
  double lambda = 0.0, step = 1.0, lambda_prev = -1.0;
  std::vector<double> D = root, D_prev;
  StageResult r = finish(root, HUGE_VAL, tol);
  for (int solve = 0; solve < kContinuationSolves && !P.budget_spent; ++solve) {
    const double next = std::min(1.0, lambda + step);
    std::vector<double> start = D;
    if (lambda_prev >= 0.0)  // secant predictor along the path of roots
      for (std::size_t i = 0; i < n; ++i)
        start[i] = std::max(0.0, D[i] + (next - lambda) / (lambda - lambda_prev) * (D[i] - D_prev[i]));
    {
      const Resized at(P, next);
      r = slsqp ? run_slsqp(P, false, start, tol, max_eval) : newton_first_order(P, start, tol);
    }
    if (!r.feasible) {
      step *= 0.5;
      continue;
    }
    if (next == 1.0) return r;
    D_prev = D, lambda_prev = lambda;
    D = r.D, lambda = next;
    step = std::min(2.0 * step, 1.0 - lambda);
  }
  r.feasible = false;
  return r;
}

}  // namespace freeflex::detail
