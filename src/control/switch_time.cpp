// Bang-bang switch-time design with NLopt SLSQP (see the header for the formulation).
#include "freeflex/control/switch_time.hpp"

#include <nlopt.hpp>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cmath>
#include <complex>
#include <random>
#include <sstream>
#include <stdexcept>

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/sim/integrator.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string fmt(double v) { return util::format_number(v, 10); }

void validate_actuator(const FlexibleBody& body, int actuator, const std::string& where) {
  const int ne = static_cast<int>(body.elements().size());
  if (actuator < 0 || actuator >= ne)
    throw std::invalid_argument(where + ": actuator = " + std::to_string(actuator) + " is not an element of the body (0.." +
                                std::to_string(ne - 1) + ")");
  const ForceElement& el = body.elements()[actuator];
  if (el.type != ForceElement::Type::Torque)
    throw std::invalid_argument(where + ": actuator " + std::to_string(actuator) + " ('" + el.name +
                                "') must be a torque, got a force or thruster");
  const double L = body.beam().length();
  if (std::abs(body.element_x(actuator)) > 1e-9 * L)
    throw std::invalid_argument(where + ": actuator '" + el.name + "' must act at o (x = 0), got x = " +
                                fmt(body.element_x(actuator)) + " m");
  const ModalIntegrals& mi = body.integrals();
  if (std::abs(mi.S_o) > 1e-9 * mi.m * L)
    throw std::invalid_argument(where + ": o must be the mass centre (S_o = 0), got S_o = " + fmt(mi.S_o) + " kg m");
}

/// The first `modes` elastic modes of the rest model (eq. 4.1, at attitude theta) that the
/// torque excites: frequencies, mass-normalized shapes, participation vᵀ g.
struct TargetModes {
  Eigen::VectorXd omega, participation;
  Eigen::MatrixXd shapes;  // N x k
  Eigen::MatrixXd M0;      // 𝕄0 at theta
};

TargetModes target_modes(const FlexibleBody& body, int actuator, double theta, int modes, const std::string& where) {
  const int N = body.dofs();
  ExcitedModes em = excited_modes(body, actuator, theta);
  if (static_cast<int>(em.excited.size()) < modes)
    throw std::invalid_argument(where + ": the actuator excites only " + std::to_string(em.excited.size()) +
                                " elastic modes of this basis, asked for modes = " + std::to_string(modes));
  TargetModes t;
  t.omega.resize(modes);
  t.participation.resize(modes);
  t.shapes.resize(N, modes);
  for (int i = 0; i < modes; ++i) {
    const int j = em.excited[static_cast<std::size_t>(i)];
    t.omega(i) = std::sqrt(std::max(0.0, em.eigenvalues(3 + j)));
    t.participation(i) = em.participation(j);
    t.shapes.col(i) = em.eigenvectors.col(3 + j);
  }
  t.M0 = std::move(em.M0);
  return t;
}

}  // namespace

ExcitedModes excited_modes(const FlexibleBody& body, int element, double theta) {
  const int N = body.dofs(), n = body.n();
  ExcitedModes m;
  m.M0.resize(N, N);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(n);
  body.mass_matrix(theta, q0, m.M0);
  Eigen::MatrixXd K0 = Eigen::MatrixXd::Zero(N, N);
  K0.bottomRightCorner(n, n) = body.integrals().K;
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K0, m.M0);
  m.eigenvalues = es.eigenvalues();
  m.eigenvectors = es.eigenvectors();
  Eigen::VectorXd g(N);
  body.element_force(element, theta, q0, g);
  m.participation = m.eigenvectors.rightCols(n).transpose() * g;
  const double pmax = m.participation.cwiseAbs().maxCoeff();
  for (int j = 0; j < n; ++j)
    if (std::abs(m.participation(j)) > 1e-8 * pmax) m.excited.push_back(j);
  return m;
}

namespace {

std::vector<double> switches_of(const std::vector<double>& durations, double& T) {
  std::vector<double> s;
  double t = 0.0;
  for (std::size_t i = 0; i + 1 < durations.size(); ++i) {
    t += durations[i];
    s.push_back(t);
  }
  T = t + durations.back();
  return s;
}

/// Rigid end state θ0(T), θ0'(T) of durations Δ (signs +, −, ...) and their gradients.
void rigid_end(const std::vector<double>& D, double a, double& theta, double& rate, std::vector<double>* dtheta,
               std::vector<double>* drate) {
  const int M = static_cast<int>(D.size());
  theta = 0.0;
  rate = 0.0;
  std::vector<double> rate_after(M);
  for (int i = 0; i < M; ++i) {
    const double acc = (i % 2 == 0 ? a : -a);
    theta += rate * D[i] + 0.5 * acc * D[i] * D[i];
    rate += acc * D[i];
    rate_after[i] = rate;
  }
  if (dtheta) {
    dtheta->assign(M, 0.0);
    drate->assign(M, 0.0);
    double after = 0.0;  // time after interval i
    for (int i = M - 1; i >= 0; --i) {
      const double acc = (i % 2 == 0 ? a : -a);
      (*dtheta)[i] = rate_after[i] + acc * after;  // more time at acceleration acc, inserted
      (*drate)[i] = acc;
      after += D[i];
    }
  }
}

struct Problem {
  const FlexibleBody* body = nullptr;
  int actuator = 0, k = 0;
  double I_o = 0.0, tau = 0.0, a = 0.0, dtheta = 0.0;
  double scale = 1.0;  // sqrt(I_o) θ'* : modal constraints divided by it
  TargetModes modes;
  double rtol = 1e-11, atol = 1e-14;
  int simulations = 0;
  std::function<void(int)> progress;  // SwitchTimeOptions::progress
  std::string last_error;
};

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

/// First-order simulation of a design: x1(T).
bool simulate(Problem& P, const std::vector<double>& D, Eigen::VectorXd& x1_end, double* peak_rate = nullptr) {
  double T = 0.0;
  const std::vector<double> sw = switches_of(D, T);
  ++P.simulations;
  if (P.progress) P.progress(P.simulations);
  try {
    const BangBangRotation traj(P.I_o, P.tau, sw, T);
    const int act = P.actuator;
    const FirstOrderModel model(
        *P.body, traj,
        [&traj, act](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) {
          c.setZero();
          c(act) = traj.torque(at);
        },
        {});
    const int N = P.body->dofs();
    OdeSystem sys;
    sys.dim = 2 * N;
    const Eigen::VectorXd none(0);
    sys.rhs = [&model, &none](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                              Eigen::Ref<Eigen::VectorXd> xd) {
      model.rhs(at, x, none, xd);
      return xd.allFinite();
    };
    IntegratorOptions io;
    io.method = IntegratorOptions::Method::Adams;  // undamped oscillations, not stiff
    io.rtol = P.rtol;
    io.atol = P.atol;
    const IntegrationResult ir = integrate(sys, Eigen::VectorXd::Zero(2 * N), {0.0, T}, sw, io);
    if (!ir.ok) {
      P.last_error = ir.message;
      return false;
    }
    x1_end = ir.x.row(ir.x.rows() - 1).transpose();
    if (peak_rate) {
      double pk = 0.0;
      for (double s : sw) pk = std::max(pk, std::abs(traj.at(Instant::at(s)).vel(2)));
      *peak_rate = pk;
    }
    return true;
  } catch (const std::exception& e) {
    P.last_error = e.what();
    return false;
  }
}

/// Modal constraints [ω η, η'] / scale of the first-order state at T.
void modal_from_state(const Problem& P, const Eigen::VectorXd& x1, double* c) {
  const int N = P.body->dofs();
  const Eigen::VectorXd eta = P.modes.shapes.transpose() * (P.modes.M0 * x1.head(N));
  const Eigen::VectorXd eta_d = P.modes.shapes.transpose() * (P.modes.M0 * x1.tail(N));
  for (int j = 0; j < P.k; ++j) {
    c[2 * j] = P.modes.omega(j) * eta(j) / P.scale;
    c[2 * j + 1] = eta_d(j) / P.scale;
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

BangBangRotation::BangBangRotation(double I_o, double torque_limit_Nm, std::vector<double> switch_times,
                                   double duration_s)
    : tau_max_(torque_limit_Nm), accel_(torque_limit_Nm / I_o), duration_(duration_s) {
  if (!(I_o > 0.0) || !(torque_limit_Nm > 0.0) || !std::isfinite(I_o) || !std::isfinite(torque_limit_Nm))
    throw std::invalid_argument("bang-bang rotation: I_o and the torque limit must be finite and > 0");
  t_.push_back(0.0);
  for (double s : switch_times) {  // equal times: an interval of zero length
    if (!(s >= t_.back()) || !(s <= duration_s))
      throw std::invalid_argument("bang-bang rotation: switch times must ascend inside [0, " + fmt(duration_s) +
                                  "], got " + fmt(s));
    t_.push_back(s);
  }
  if (!(duration_s > 0.0) || !(duration_s >= t_.back()) || !std::isfinite(duration_s))
    throw std::invalid_argument("bang-bang rotation: the duration must follow the last switch, got " + fmt(duration_s));
  t_.push_back(duration_s);
  theta_.assign(t_.size(), 0.0);
  rate_.assign(t_.size(), 0.0);
  for (std::size_t i = 0; i + 1 < t_.size(); ++i) {
    const double acc = (i % 2 == 0 ? accel_ : -accel_), h = t_[i + 1] - t_[i];
    theta_[i + 1] = theta_[i] + rate_[i] * h + 0.5 * acc * h * h;
    rate_[i + 1] = rate_[i] + acc * h;
  }
}

int BangBangRotation::piece(double mid) const {
  const int M = static_cast<int>(t_.size()) - 1;  // intervals; index M: after the end
  if (mid >= duration_) return M;
  int p = 0;
  while (p + 1 < M && mid >= t_[p + 1]) ++p;  // zero-length intervals are skipped
  return p;
}

RigidState BangBangRotation::at(const Instant& when) const {
  const int p = piece(when.piece_mid);
  RigidState s;
  const int M = static_cast<int>(t_.size()) - 1;
  const double acc = p == M ? 0.0 : (p % 2 == 0 ? accel_ : -accel_);
  const double dt = when.t - t_[p];
  s.pos(2) = theta_[p] + rate_[p] * dt + 0.5 * acc * dt * dt;
  s.vel(2) = rate_[p] + acc * dt;
  s.acc(2) = acc;
  return s;
}

std::vector<double> BangBangRotation::breakpoints() const { return std::vector<double>(t_.begin() + 1, t_.end()); }

double BangBangRotation::torque(const Instant& when) const {
  const int p = piece(when.piece_mid);
  const int M = static_cast<int>(t_.size()) - 1;
  return p == M ? 0.0 : (p % 2 == 0 ? tau_max_ : -tau_max_);
}

TimeProfile BangBangRotation::profile() const {
  std::vector<double> v;
  for (std::size_t i = 0; i + 1 < t_.size(); ++i) v.push_back(i % 2 == 0 ? tau_max_ : -tau_max_);
  return TimeProfile(TimeProfile::Kind::Steps, t_, v);
}

TimeProfile SwitchTimeResult::torque_profile() const {
  std::vector<double> t{0.0};
  t.insert(t.end(), switch_times.begin(), switch_times.end());
  t.push_back(duration_s);
  std::vector<double> v;
  for (std::size_t i = 0; i + 1 < t.size(); ++i) v.push_back(i % 2 == 0 ? torque_limit_Nm : -torque_limit_Nm);
  return TimeProfile(TimeProfile::Kind::Steps, t, v);
}

BangBangResidual bang_bang_residual(const FlexibleBody& body, int actuator, double torque_limit_Nm,
                                    const std::vector<double>& switch_times, double duration_s, int modes, double rtol,
                                    double atol) {
  const std::string where = "bang_bang_residual";
  validate_actuator(body, actuator, where);
  if (modes < 0) throw std::invalid_argument(where + ": modes must be >= 0");
  const BangBangRotation traj(body.integrals().I_o, torque_limit_Nm, switch_times, duration_s);
  Problem P;
  P.body = &body;
  P.actuator = actuator;
  P.I_o = body.integrals().I_o;
  P.tau = torque_limit_Nm;
  P.a = torque_limit_Nm / P.I_o;
  P.rtol = rtol;
  P.atol = atol;
  P.k = modes;
  const double theta_f = traj.at(Instant{duration_s, duration_s + 1.0}).pos(2);
  P.modes = target_modes(body, actuator, theta_f, modes, where);
  std::vector<double> D;
  double prev = 0.0;
  for (double s : switch_times) D.push_back(s - prev), prev = s;
  D.push_back(duration_s - prev);
  BangBangResidual r;
  r.omega_rad_s = P.modes.omega;
  if (!simulate(P, D, r.x1_end, &r.peak_rate_rad_s)) {
    r.message = P.last_error;
    return r;
  }
  const int N = body.dofs();
  const Eigen::VectorXd eta = P.modes.shapes.transpose() * (P.modes.M0 * r.x1_end.head(N));
  const Eigen::VectorXd eta_d = P.modes.shapes.transpose() * (P.modes.M0 * r.x1_end.tail(N));
  r.energy_J = 0.5 * (eta_d.cwiseAbs2() + P.modes.omega.cwiseAbs2().cwiseProduct(eta.cwiseAbs2()));
  r.rigid_kinetic_peak_J = 0.5 * P.I_o * r.peak_rate_rad_s * r.peak_rate_rad_s;
  r.ok = true;
  return r;
}

SwitchTimeResult design_switch_times(const FlexibleBody& body, const SwitchTimeOptions& o) {
  const std::string where = "design_switch_times";
  validate_actuator(body, o.actuator, where);
  if (!(o.rotation_rad > 0.0) || !std::isfinite(o.rotation_rad))
    throw std::invalid_argument(where + ": rotation_rad = " + fmt(o.rotation_rad) + ", must be finite and > 0");
  if (!(o.torque_limit_Nm > 0.0) || !std::isfinite(o.torque_limit_Nm))
    throw std::invalid_argument(where + ": torque_limit_Nm = " + fmt(o.torque_limit_Nm) + ", must be finite and > 0");
  if (o.modes < 0 || o.modes > 4)
    throw std::invalid_argument(where + ": modes = " + std::to_string(o.modes) + ", must be in [0, 4]");
  if (!(o.rtol > 0.0) || !(o.atol > 0.0) || !(o.constraint_tolerance > 0.0) || o.starts < 1 || o.max_evaluations < 1)
    throw std::invalid_argument(where + ": rtol, atol, constraint_tolerance must be > 0 and starts, max_evaluations >= 1");
  const auto clock0 = std::chrono::steady_clock::now();

  Problem P;
  P.body = &body;
  P.actuator = o.actuator;
  P.k = o.modes;
  P.I_o = body.integrals().I_o;
  P.tau = o.torque_limit_Nm;
  P.a = P.tau / P.I_o;
  P.dtheta = o.rotation_rad;
  P.rtol = o.rtol;
  P.atol = o.atol;
  P.progress = o.progress;
  P.modes = target_modes(body, o.actuator, o.rotation_rad, o.modes, where);
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

InputShaper zv_shaper(double omega, double zeta) {
  if (!(omega > 0.0) || !(zeta >= 0.0) || !(zeta < 1.0))
    throw std::invalid_argument("zv_shaper: need omega > 0 and 0 <= zeta < 1");
  const double K = std::exp(-zeta * M_PI / std::sqrt(1.0 - zeta * zeta));
  const double Td = 2.0 * M_PI / (omega * std::sqrt(1.0 - zeta * zeta));
  return {{0.0, 0.5 * Td}, {1.0 / (1.0 + K), K / (1.0 + K)}};
}

InputShaper zvd_shaper(double omega, double zeta) {
  if (!(omega > 0.0) || !(zeta >= 0.0) || !(zeta < 1.0))
    throw std::invalid_argument("zvd_shaper: need omega > 0 and 0 <= zeta < 1");
  const double K = std::exp(-zeta * M_PI / std::sqrt(1.0 - zeta * zeta));
  const double Td = 2.0 * M_PI / (omega * std::sqrt(1.0 - zeta * zeta));
  const double s = 1.0 + 2.0 * K + K * K;
  return {{0.0, 0.5 * Td, Td}, {1.0 / s, 2.0 * K / s, K * K / s}};
}

}  // namespace freeflex
