// The continuous trajectory a collocation solution stands for: Hermite states, piecewise
// controls, and the interval error estimates of mesh refinement.
#include "freeflex/trajopt/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace freeflex {

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

std::string shape(const Eigen::MatrixXd& m) {
  return std::to_string(m.rows()) + " x " + std::to_string(m.cols());
}

}  // namespace

CollocationTrajectory::CollocationTrajectory(ManeuverDynamics dynamics, Transcription transcription, Eigen::VectorXd t,
                                             Eigen::MatrixXd x, Eigen::MatrixXd u, Eigen::MatrixXd u_mid)
    : dyn_(std::move(dynamics)), tr_(transcription), t_(std::move(t)), x_(std::move(x)), u_(std::move(u)),
      u_mid_(std::move(u_mid)) {
  const Eigen::Index K = t_.size(), nu = dyn_.nu();
  if (K < 2) throw std::invalid_argument("collocation trajectory: t has " + std::to_string(K) + " knots, expected >= 2");
  for (Eigen::Index i = 1; i < K; ++i)
    if (!(t_(i) > t_(i - 1)))
      throw std::invalid_argument("collocation trajectory: knot times must be strictly ascending (t[" +
                                  std::to_string(i) + "] = " + std::to_string(t_(i)) + ")");
  const int nx = dyn_.nx();
  if (x_.rows() != K || x_.cols() != nx)
    throw std::invalid_argument("collocation trajectory: x is " + shape(x_) + ", expected " + std::to_string(K) +
                                " x " + std::to_string(nx));
  if (u_.rows() != K || u_.cols() != nu)
    throw std::invalid_argument("collocation trajectory: u is " + shape(u_) + ", expected " + std::to_string(K) +
                                " x " + std::to_string(nu));
  if (has_midpoints(tr_) && (u_mid_.rows() != K - 1 || u_mid_.cols() != nu))
    throw std::invalid_argument("collocation trajectory: u_mid is " + shape(u_mid_) + ", expected " +
                                std::to_string(K - 1) + " x " + std::to_string(nu) + " for Hermite-Simpson");
  f_.resize(K, nx);
  for (Eigen::Index i = 0; i < K; ++i) f_.row(i) = dyn_.eval(x_.row(i).transpose(), u_.row(i).transpose()).transpose();
}

std::vector<double> CollocationTrajectory::breakpoints() const {
  return std::vector<double>(t_.data() + 1, t_.data() + t_.size() - 1);
}

int CollocationTrajectory::interval_of(double t) const {
  const double* b = t_.data();
  const double* e = b + t_.size();
  const int k = static_cast<int>(std::upper_bound(b, e, t) - b) - 1;
  return std::clamp(k, 0, intervals() - 1);
}

Eigen::VectorXd CollocationTrajectory::state_in(int k, double t, Eigen::VectorXd* rate) const {
  const double h = t_(k + 1) - t_(k), s = (t - t_(k)) / h, s2 = s * s, s3 = s2 * s;
  const auto xa = x_.row(k).transpose(), xb = x_.row(k + 1).transpose();
  const auto fa = f_.row(k).transpose(), fb = f_.row(k + 1).transpose();
  if (rate)
    *rate = ((6 * s2 - 6 * s) / h) * xa + (3 * s2 - 4 * s + 1) * fa + ((6 * s - 6 * s2) / h) * xb + (3 * s2 - 2 * s) * fb;
  return (2 * s3 - 3 * s2 + 1) * xa + (h * (s3 - 2 * s2 + s)) * fa + (3 * s2 - 2 * s3) * xb + (h * (s3 - s2)) * fb;
}

Eigen::VectorXd CollocationTrajectory::control_in(int k, double t) const {
  const double s = (t - t_(k)) / (t_(k + 1) - t_(k));
  if (tr_ == Transcription::Trapezoidal) return ((1 - s) * u_.row(k) + s * u_.row(k + 1)).transpose();
  // Lagrange basis on s = 0, 1/2, 1.
  return (2 * (s - 0.5) * (s - 1) * u_.row(k) - 4 * s * (s - 1) * u_mid_.row(k) + 2 * s * (s - 0.5) * u_.row(k + 1))
      .transpose();
}

RigidState CollocationTrajectory::at(const Instant& when) const {
  const int k = interval_of(when.piece_mid);
  const double t = std::clamp(when.t, t_begin(), t_end());
  const Vector6d x = state_in(k, t, nullptr).head<6>();
  const Vector6d f = dyn_.rigid().eval(x, control_in(k, t));
  RigidState r;
  r.pos = x.head<3>();
  r.vel = x.tail<3>();
  r.acc = f.tail<3>();
  return r;
}

Eigen::VectorXd CollocationTrajectory::control_at(double t) const { return control_at(Instant::at(t)); }

Eigen::VectorXd CollocationTrajectory::control_at(const Instant& when) const {
  if (when.t < t_begin() || when.t > t_end()) return Eigen::VectorXd::Zero(dyn_.nu());
  return control_in(interval_of(when.piece_mid), when.t);
}

Vector6d CollocationTrajectory::state_at(double t) const { return state_at(Instant::at(t)); }

Vector6d CollocationTrajectory::state_at(const Instant& when) const {
  return state_in(interval_of(when.piece_mid), std::clamp(when.t, t_begin(), t_end()), nullptr).head<6>();
}

Eigen::VectorXd CollocationTrajectory::full_state_at(const Instant& when) const {
  return state_in(interval_of(when.piece_mid), std::clamp(when.t, t_begin(), t_end()), nullptr);
}

Eigen::VectorXd CollocationTrajectory::interval_errors() const {
  // 5-point Gauss–Legendre on [0, 1].
  static const double node[5] = {0.04691007703066800, 0.23076534494715845, 0.5, 0.76923465505284155,
                                 0.95308992296933200};
  static const double weight[5] = {0.11846344252809454, 0.23931433524968324, 0.28444444444444444,
                                   0.23931433524968324, 0.11846344252809454};
  Eigen::VectorXd e(intervals());
  for (int k = 0; k < intervals(); ++k) {
    const double h = t_(k + 1) - t_(k);
    Eigen::VectorXd acc = Eigen::VectorXd::Zero(dyn_.nx()), rate;
    for (int q = 0; q < 5; ++q) {
      const double t = t_(k) + node[q] * h;
      const Eigen::VectorXd x = state_in(k, t, &rate);
      acc += (weight[q] * h) * (rate - dyn_.eval(x, control_in(k, t))).cwiseAbs();
    }
    e(k) = acc.maxCoeff();
  }
  return e;
}

}  // namespace freeflex
