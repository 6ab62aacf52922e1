// Modal integration variables (docs/theory.md section 8).
#include "sim/modal_variables.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace freeflex {
namespace {

Eigen::Matrix2d rotation(double a) {
  const double c = std::cos(a), s = std::sin(a);
  Eigen::Matrix2d C;
  C << c, -s, s, c;
  return C;
}

/// J v with J = dC/dθ at θ = 0 (a quarter turn).
Eigen::Vector2d quarter_turn(const Eigen::Vector2d& v) { return {-v(1), v(0)}; }

}  // namespace

ModalVariables::ModalVariables(const FlexibleBody& body, PhysicalRhs physical,
                               std::shared_ptr<const RigidTrajectory> frame)
    : n_(body.n()), N_(body.dofs()), physical_(std::move(physical)), frame_(std::move(frame)) {
  if (!physical_) throw std::invalid_argument("ModalVariables: the physical right-hand side is not set");
  const int n = n_, N = N_;
  // Elastic mass with the rigid momenta held (Schur complement) and the modes at rest.
  const RestModes modes = rest_modes(body);
  T_ = modes.T;
  Phi_ = modes.Phi;  // Φᵀ M_c Φ = I
  Phi_inv_ = Phi_.transpose() * modes.M_c;
  omega2_ = modes.omega2;
  omega_ = omega2_.cwiseSqrt();
  // Modal damping enters the reference oscillators (decay of a, b); a mode damped at or
  // above critical keeps its damping in the modal force instead.
  sigma_.setZero(n);
  if (body.damped()) {
    Eigen::MatrixXd V(N, n);  // elastic modes of the whole body at rest
    V.topRows(3) = -T_ * Phi_;
    V.bottomRows(n) = Phi_;
    const Eigen::MatrixXd Dm = V.transpose() * body.damping() * V;
    for (int k = 0; k < n; ++k) {
      const double s = 0.5 * Dm(k, k);
      sigma_(k) = s < 0.99 * omega_(k) ? s : 0.0;
    }
  }
  omega_d_ = (omega2_ - sigma_.cwiseAbs2()).cwiseSqrt();
  // atol in the variables: an error of atol in a_k moves q (and R, θ through T) by at most
  // atol, an error of atol in b_k moves q' by at most atol.
  atol_scale_.setOnes(2 * N);
  for (int k = 0; k < n; ++k) {
    const double reach = std::max(Phi_.col(k).cwiseAbs().maxCoeff(), (T_ * Phi_.col(k)).cwiseAbs().maxCoeff());
    atol_scale_(3 + k) = 1.0 / reach;
    atol_scale_(N + 3 + k) = 1.0 / (reach * omega_(k));
  }
  rho_s_.setZero(n);
  eta_static_.setZero(n);
  x_.setZero(2 * N);
  x_dot_.setZero(2 * N);
  for (auto* v : {&cos_, &sin_, &u_, &v_, &eta_, &eta_dot_, &f_}) v->setZero(n);
  Tq_.setZero(3);
  Tqd_.setZero(3);
  Tqdd_.setZero(3);
}

ModalVariables::Frame ModalVariables::frame_at(const Instant& at) const {
  if (!frame_) return {0.0, 0.0, 0.0, true};
  const RigidState s = frame_->at(at);
  return {s.pos(2), s.vel(2), s.acc(2), false};
}

OdeSystem ModalVariables::system(std::function<std::string()> last_error) {
  OdeSystem sys;
  sys.dim = size();
  sys.rhs = [this](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> yd) {
    return rhs(at, y, yd);
  };
  sys.last_error = std::move(last_error);
  sys.variables.enter_piece = [this](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                                     Eigen::Ref<Eigen::VectorXd> y) { return enter_piece(at, x, y); };
  sys.variables.to_x = [this](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y,
                              Eigen::Ref<Eigen::VectorXd> x) { to_physical(at, y, x); };
  sys.variables.atol_scale = atol_scale_;
  return sys;
}

bool ModalVariables::enter_piece(const Instant& start, const Eigen::Ref<const Eigen::VectorXd>& x,
                                 Eigen::Ref<Eigen::VectorXd> y) {
  const int n = n_, N = N_;
  if (!physical_(start, x, x_dot_) || !x_dot_.allFinite()) return false;
  t_s_ = start.t;
  eta_.noalias() = Phi_inv_ * x.segment(3, n);
  eta_dot_.noalias() = Phi_inv_ * x.segment(N + 3, n);
  f_.noalias() = Phi_inv_ * x_dot_.segment(N + 3, n);  // η''
  // Modal force at the start: what drives η'' + 2σ η' + ω² η.
  rho_s_ = f_ + 2.0 * sigma_.cwiseProduct(eta_dot_) + omega2_.cwiseProduct(eta_);
  eta_static_ = rho_s_.cwiseQuotient(omega2_);
  u_ = eta_ - eta_static_;
  y.segment(3, n) = u_;
  y.segment(N + 3, n) = (eta_dot_ + sigma_.cwiseProduct(u_)).cwiseQuotient(omega_d_);
  // Rigid coordinates shifted by the rigid motion the elastic deformation carries.
  Tq_.noalias() = T_ * x.segment(3, n);
  Tqd_.noalias() = T_ * x.segment(N + 3, n);
  Eigen::Vector2d s, s_dot;
  carried_translation(start, x, s, s_dot);
  y.head<2>() = x.head<2>() + s;
  y(2) = x(2) + Tq_(2);
  y.segment<2>(N) = x.segment<2>(N) + s_dot;
  y(N + 2) = x(N + 2) + Tqd_(2);
  return y.allFinite();
}

void ModalVariables::to_physical(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y,
                                 Eigen::Ref<Eigen::VectorXd> x) {
  const int n = n_, N = N_;
  const double tau = at.t - t_s_;
  for (int k = 0; k < n; ++k) {
    const double ph = omega_d_(k) * tau;
    cos_(k) = std::cos(ph);
    sin_(k) = std::sin(ph);
  }
  const auto a = y.segment(3, n);
  const auto b = y.segment(N + 3, n);
  u_ = a.cwiseProduct(cos_) + b.cwiseProduct(sin_);
  v_ = b.cwiseProduct(cos_) - a.cwiseProduct(sin_);
  eta_ = eta_static_ + u_;
  eta_dot_ = omega_d_.cwiseProduct(v_) - sigma_.cwiseProduct(u_);
  x.segment(3, n).noalias() = Phi_ * eta_;
  x.segment(N + 3, n).noalias() = Phi_ * eta_dot_;
  Tq_.noalias() = T_ * x.segment(3, n);
  Tqd_.noalias() = T_ * x.segment(N + 3, n);
  x(2) = y(2) - Tq_(2);
  x(N + 2) = y(N + 2) - Tqd_(2);
  Eigen::Vector2d s, s_dot;
  current_ = carried_translation(at, x, s, s_dot);
  x.head<2>() = y.head<2>() - s;
  x.segment<2>(N) = y.segment<2>(N) - s_dot;
}

ModalVariables::Frame ModalVariables::carried_translation(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                                                          Eigen::Vector2d& s, Eigen::Vector2d& s_dot) const {
  Frame fr = frame_at(at);
  if (fr.from_state) {
    fr.angle = x(2);
    fr.rate = x(N_ + 2);
  }
  const Eigen::Matrix2d C = rotation(fr.angle);
  const Eigen::Vector2d p = Tq_.head<2>(), pd = Tqd_.head<2>();
  s = C * p;
  s_dot = C * (pd + fr.rate * quarter_turn(p));
  return fr;
}

bool ModalVariables::rhs(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y,
                         Eigen::Ref<Eigen::VectorXd> yd) {
  const int n = n_, N = N_;
  to_physical(at, y, x_);
  if (!physical_(at, x_, x_dot_)) return false;
  const auto zdd = x_dot_.tail(N);
  // Departure of the modal force from its value at the start of the piece.
  f_.noalias() = Phi_inv_ * zdd.tail(n);
  f_ += 2.0 * sigma_.cwiseProduct(eta_dot_) + omega2_.cwiseProduct(eta_) - rho_s_;
  f_.array() /= omega_d_.array();
  yd.segment(3, n) = -sigma_.cwiseProduct(y.segment(3, n)) - sin_.cwiseProduct(f_);
  yd.segment(N + 3, n) = -sigma_.cwiseProduct(y.segment(N + 3, n)) + cos_.cwiseProduct(f_);
  // Rigid: r_s'' = r'' + d²/dt² (C(φ) T q) with the frame angle φ (θ, or θ0 of the trajectory).
  Tqdd_.noalias() = T_ * zdd.tail(n);
  Frame fr = current_;
  if (fr.from_state) fr.accel = zdd(2);
  const Eigen::Matrix2d C = rotation(fr.angle);
  const Eigen::Vector2d p = Tq_.head<2>(), pd = Tqd_.head<2>();
  yd.head<3>() = y.segment<3>(N);
  yd.segment<2>(N) = zdd.head<2>() + C * (Tqdd_.head<2>() + 2.0 * fr.rate * quarter_turn(pd) +
                                         fr.accel * quarter_turn(p) - fr.rate * fr.rate * p);
  yd(N + 2) = zdd(2) + Tqdd_(2);
  return true;
}

}  // namespace freeflex
