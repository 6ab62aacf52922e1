// Prescribed rigid motion: the profiles of the reference frame's coordinates and the
// simulation of the elastic response to them (docs/theory.md section 14, eq. 14.10).
#include "freeflex/sim/prescribed.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "model/commands.hpp"
#include "sim/range_check.hpp"
#include "util/format.hpp"
#include "util/quintic_hermite.hpp"

namespace freeflex {
namespace {
constexpr double kTwoPi = 6.283185307179586476925286766559;
using Clock = std::chrono::steady_clock;
}  // namespace

MotionProfile MotionProfile::spin_up(double final_rate, double ramp_time) {
  if (!std::isfinite(final_rate) || !(ramp_time > 0.0) || !std::isfinite(ramp_time))
    throw std::invalid_argument("MotionProfile::spin_up: final_rate = " + util::format_number(final_rate, 10) +
                                ", ramp_time = " + util::format_number(ramp_time, 10) +
                                "; expected a finite rate and a finite ramp time > 0");
  MotionProfile p;
  p.kind_ = Kind::SpinUp;
  p.rate_ = final_rate;
  p.ramp_ = ramp_time;
  return p;
}

MotionProfile MotionProfile::table(std::vector<double> t, std::vector<double> v, std::vector<double> r,
                                   std::vector<double> a) {
  const std::size_t k = t.size();
  if (k < 2 || v.size() != k || r.size() != k || a.size() != k)
    throw std::invalid_argument("MotionProfile::table: times, values, rates and accelerations must have the same size "
                                ">= 2 (got " + std::to_string(k) + ", " + std::to_string(v.size()) + ", " +
                                std::to_string(r.size()) + ", " + std::to_string(a.size()) + ")");
  if (t[0] != 0.0) throw std::invalid_argument("MotionProfile::table: the times must start at 0");
  for (std::size_t i = 0; i < k; ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(v[i]) || !std::isfinite(r[i]) || !std::isfinite(a[i]))
      throw std::invalid_argument("MotionProfile::table: entry " + std::to_string(i) + " is not finite");
    if (i > 0 && !(t[i] > t[i - 1]))
      throw std::invalid_argument("MotionProfile::table: times must ascend strictly (entry " + std::to_string(i) + ")");
  }
  MotionProfile p;
  p.kind_ = Kind::Table;
  p.t_ = std::move(t);
  p.v_ = std::move(v);
  p.r_ = std::move(r);
  p.a_ = std::move(a);
  return p;
}

Eigen::Vector3d MotionProfile::at(double t) const {
  switch (kind_) {
    case Kind::Rest:
      return Eigen::Vector3d::Zero();
    case Kind::SpinUp: {
      const double W = rate_, T = ramp_, c = T / kTwoPi;
      if (t >= T) return Eigen::Vector3d(W * T / 2 + W * (t - T), W, 0.0);
      const double w = kTwoPi / T;
      return Eigen::Vector3d((W / T) * (t * t / 2 + c * c * (std::cos(w * t) - 1.0)),
                             (W / T) * (t - c * std::sin(w * t)), (W / T) * (1.0 - std::cos(w * t)));
    }
    case Kind::Table: {
      const std::size_t k = t_.size();
      if (t >= t_.back()) return Eigen::Vector3d(v_.back() + r_.back() * (t - t_.back()), r_.back(), 0.0);
      auto it = std::upper_bound(t_.begin(), t_.end(), t);
      std::size_t i = it == t_.begin() ? 0 : static_cast<std::size_t>(it - t_.begin()) - 1;
      i = std::min(i, k - 2);
      const double h = t_[i + 1] - t_[i], s = (t - t_[i]) / h;
      const detail::QuinticHermite w(s);  // value, rate and acceleration at both ends
      auto combine = [&](const double* c) {
        return c[0] * v_[i] + c[1] * h * r_[i] + c[2] * h * h * a_[i] + c[3] * v_[i + 1] + c[4] * h * r_[i + 1] +
               c[5] * h * h * a_[i + 1];
      };
      return Eigen::Vector3d(combine(w.H), combine(w.D1) / h, combine(w.D2) / (h * h));
    }
  }
  return Eigen::Vector3d::Zero();
}

std::vector<double> MotionProfile::breakpoints() const {
  if (kind_ == Kind::SpinUp) return {ramp_};
  if (kind_ == Kind::Table) return {t_.back()};
  return {};
}

double MotionProfile::peak_rate(double t_end) const {
  switch (kind_) {
    case Kind::Rest:
      return 0.0;
    case Kind::SpinUp:
      return std::abs(rate_) * std::min(1.0, t_end >= ramp_ ? 1.0 : at(t_end)(1) / rate_);
    case Kind::Table: {
      double m = 0.0;
      for (std::size_t i = 0; i < t_.size() && t_[i] <= t_end; ++i) m = std::max(m, std::abs(r_[i]));
      return std::max(m, std::abs(at(t_end)(1)));
    }
  }
  return 0.0;
}

PrescribedMotion::PrescribedMotion(MotionProfile x, MotionProfile y, MotionProfile theta, double hub_radius)
    : x_(std::move(x)), y_(std::move(y)), theta_(std::move(theta)), r_(hub_radius) {
  if (!std::isfinite(hub_radius))
    throw std::invalid_argument("PrescribedMotion: hub_radius = " + util::format_number(hub_radius, 10) +
                                ", expected a finite value");
}

RigidState PrescribedMotion::at(const Instant& when) const {
  const Eigen::Vector3d X = x_.at(when.t), Y = y_.at(when.t), T = theta_.at(when.t);
  RigidState s;
  const double c = std::cos(T(0)), sn = std::sin(T(0));
  const Eigen::Vector2d Ce1(c, sn), CJe1(-sn, c);
  s.pos << Eigen::Vector2d(X(0), Y(0)) + r_ * Ce1, T(0);
  s.vel << Eigen::Vector2d(X(1), Y(1)) + r_ * T(1) * CJe1, T(1);
  s.acc << Eigen::Vector2d(X(2), Y(2)) + r_ * (T(2) * CJe1 - T(1) * T(1) * Ce1), T(2);
  return s;
}

std::vector<double> PrescribedMotion::breakpoints() const {
  std::vector<double> b;
  for (const MotionProfile* p : {&x_, &y_, &theta_})
    for (double t : p->breakpoints()) b.push_back(t);
  std::sort(b.begin(), b.end());
  b.erase(std::unique(b.begin(), b.end()), b.end());
  return b;
}

SimulationResult simulate_prescribed(const FlexibleBody& body, const Excitation& excitation,
                                     const PrescribedMotion& motion, const SimulationOptions& options,
                                     bool first_order) {
  const auto t0 = Clock::now();
  const int n = body.n(), N = body.dofs(), ne = static_cast<int>(body.elements().size());
  const FullModel full(body);
  const auto commands = [&excitation](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) {
    detail::evaluate_commands(excitation, at, c);
  };
  const FirstOrderModel linear(body, motion, commands, {});
  auto fd = std::make_shared<FullModel::Data>(full.create_data());
  auto od = std::make_shared<FirstOrderModel::Data>(linear.create_data());
  auto u = std::make_shared<Eigen::VectorXd>(ne);
  const Eigen::VectorXd none(0);
  OdeSystem sys;
  sys.dim = 2 * n;
  if (first_order) {
    sys.rhs = [&linear, od, &none](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& xq,
                                   Eigen::Ref<Eigen::VectorXd> xd) {
      xd = linear.prescribed_rhs(*od, at, xq, none);
      return xd.allFinite();
    };
  } else {
    sys.rhs = [&full, &motion, &excitation, fd, u](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& xq,
                                                   Eigen::Ref<Eigen::VectorXd> xd) {
      detail::evaluate_commands(excitation, at, *u);
      full.prescribed_rhs(*fd, motion.at(at), xq, *u);
      xd = fd->xq_dot;
      return xd.allFinite();
    };
    // Work on the body, ż·(G − D ż + λ) with λ the force that holds the prescribed motion
    // (the rigid rows of the residual; its q rows vanish): dE/dt for the energy balance.
    auto wd = std::make_shared<FullModel::Data>(full.create_data());
    auto uq = std::make_shared<Eigen::VectorXd>(ne);
    if (options.energy_balance) sys.quadrature_dim = 1;
    sys.quadrature = [&full, &body, &motion, &excitation, wd, uq, n, N](
                         const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& xq, Eigen::Ref<Eigen::VectorXd> w) {
      detail::evaluate_commands(excitation, at, *uq);
      const RigidState s = motion.at(at);
      full.prescribed_rhs(*wd, s, xq, *uq);
      Eigen::VectorXd z(N), zd(N), zdd(N);
      z << s.pos, xq.head(n);
      zd << s.vel, xq.tail(n);
      zdd << s.acc, wd->xq_dot.tail(n);
      const Eigen::VectorXd lambda = full.constraint_force(z, zd, zdd, *uq);
      double p = zd.dot(body.generalized_force(s.pos(2), xq.head(n), *uq)) + zd.head<3>().dot(lambda);
      if (body.damped()) p -= zd.dot(body.damping() * zd);
      w(0) = p;
      return true;
    };
  }
  sys.last_error = [] { return std::string("the right-hand side is not finite"); };
  sys.range_check = detail::deflection_check(body, options, 0);
  std::vector<double> cuts;
  for (double b : excitation.breakpoints())
    if (b > 0.0 && b < options.duration_s) cuts.push_back(b);
  for (double b : motion.breakpoints())
    if (b > 0.0 && b < options.duration_s) cuts.push_back(b);
  std::sort(cuts.begin(), cuts.end());
  std::vector<double> kept;  // leave out cuts a roundoff away from a neighbour or an end
  double last = 0.0;
  for (double t : cuts)
    if (t > last && !roundoff_span(last, t) && !roundoff_span(t, options.duration_s)) kept.push_back(last = t);
  const IntegrationResult ir = integrate(sys, Eigen::VectorXd::Zero(2 * n), output_times(options), kept, options.integrator);
  SimulationResult r;
  r.status = ir.status;
  r.message = ir.message;
  r.t = ir.t;
  const int T = static_cast<int>(ir.t.size());
  r.z.resize(T, N);
  r.z_dot.resize(T, N);
  for (int i = 0; i < T; ++i) {
    const RigidState s = motion.at(Instant::at(ir.t(i)));
    r.z.row(i) << s.pos.transpose(), ir.x.row(i).head(n);
    r.z_dot.row(i) << s.vel.transpose(), ir.x.row(i).tail(n);
  }
  if (sys.quadrature_dim == 1) r.work_J = ir.quadrature.col(0);  // energy_balance on (full model)
  r.rhs_evaluations = ir.rhs_evaluations;
  r.steps = ir.steps;
  r.wall_time_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return r;
}

}  // namespace freeflex
