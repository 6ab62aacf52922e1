// The zero-order (rigid) model and the rigid trajectories the first-order model is built
// about: sampled (quintic Hermite) and continued at rest past their end.
#include "freeflex/dynamics/zero_order.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dynamics/body_kernels.hpp"
#include "util/quintic_hermite.hpp"

namespace freeflex {

Eigen::Vector3d ZeroOrderModel::acceleration(const Eigen::Ref<const Eigen::VectorXd>& x0,
                                             const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  const ModalIntegrals& mi = body_.integrals();
  const int n = body_.n();
  const double th = x0(2), thd = x0(5), c = std::cos(th), s = std::sin(th);
  // Scratch kept per thread: this runs thousands of times per replay or simulation, where
  // two allocations per call cost more than the arithmetic.
  thread_local Eigen::VectorXd q0, G;
  if (q0.size() != n) q0 = Eigen::VectorXd::Zero(n);
  G.resize(3 + n);
  detail::generalized_force(body_, th, q0, commands, G);
  // eq. 6.3: C J s0 = S_o [-sin, cos], C s0 = S_o [cos, sin]
  Eigen::Matrix3d Mrr;
  Mrr << mi.m, 0.0, -mi.S_o * s,  //
      0.0, mi.m, mi.S_o * c,      //
      -mi.S_o * s, mi.S_o * c, mi.I_o;
  const Eigen::Vector3d rhs(G(0) + thd * thd * mi.S_o * c, G(1) + thd * thd * mi.S_o * s, G(2));
  return Mrr.ldlt().solve(rhs);
}

Eigen::Matrix<double, 6, 1> ZeroOrderModel::rhs(const Eigen::Ref<const Eigen::VectorXd>& x0,
                                                const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  Eigen::Matrix<double, 6, 1> x0_dot;
  x0_dot.head<3>() = x0.tail<3>();
  x0_dot.tail<3>() = acceleration(x0, commands);
  return x0_dot;
}

SampledRigidTrajectory::SampledRigidTrajectory(std::vector<Piece> pieces) : pieces_(std::move(pieces)) {
  if (pieces_.empty()) throw std::invalid_argument("rigid trajectory: at least one piece is required");
  for (std::size_t p = 0; p < pieces_.size(); ++p) {
    const Piece& pc = pieces_[p];
    if (pc.t.size() < 2 || pc.samples.size() != pc.t.size())
      throw std::invalid_argument("rigid trajectory: piece " + std::to_string(p + 1) +
                                  " needs at least two times and one sample per time");
    for (std::size_t i = 1; i < pc.t.size(); ++i)
      if (!(pc.t[i] > pc.t[i - 1]))
        throw std::invalid_argument("rigid trajectory: times must be strictly ascending");
    if (p > 0 && pc.t.front() != pieces_[p - 1].t.back())
      throw std::invalid_argument("rigid trajectory: piece " + std::to_string(p + 1) +
                                  " must start where the previous one ends");
  }
}

std::vector<double> SampledRigidTrajectory::breakpoints() const {
  std::vector<double> b;
  for (std::size_t p = 1; p < pieces_.size(); ++p) b.push_back(pieces_[p].t.front());
  return b;
}

RigidState SampledRigidTrajectory::at(const Instant& when) const {
  std::size_t p = 0;
  while (p + 1 < pieces_.size() && when.piece_mid >= pieces_[p + 1].t.front()) ++p;
  const Piece& pc = pieces_[p];
  const double t = when.t;
  // interval [t_i, t_i+1] containing t (clamped: outside the span the end polynomial extends)
  auto it = std::upper_bound(pc.t.begin(), pc.t.end(), t);
  std::size_t i = (it == pc.t.begin()) ? 0 : static_cast<std::size_t>(it - pc.t.begin()) - 1;
  i = std::min(i, pc.t.size() - 2);
  const double h = pc.t[i + 1] - pc.t[i], s = (t - pc.t[i]) / h;
  const RigidState& a = pc.samples[i];
  const RigidState& b = pc.samples[i + 1];
  const detail::QuinticHermite w(s);  // basis on s in [0, 1] and its first two derivatives in s
  auto combine = [&](const double* c) {
    return (c[0] * a.pos + c[1] * h * a.vel + c[2] * h * h * a.acc + c[3] * b.pos + c[4] * h * b.vel +
            c[5] * h * h * b.acc)
        .eval();
  };
  RigidState r;
  r.pos = combine(w.H);
  r.vel = combine(w.D1) / h;
  r.acc = combine(w.D2) / (h * h);
  return r;
}

std::vector<double> SampledRigidTrajectory::knots() const {
  std::vector<double> k;
  for (const Piece& p : pieces_) k.insert(k.end(), p.t.begin(), p.t.end());
  return k;
}

RigidState ExtendedTrajectory::at(const Instant& when) const {
  const double end = inner_->t_end();
  if (when.piece_mid <= end && when.t <= end) return inner_->at(when);
  RigidState s = inner_->at({end, end});
  s.pos += s.vel * (when.t - end);
  s.acc.setZero();
  return s;
}

std::vector<double> ExtendedTrajectory::breakpoints() const {
  std::vector<double> b = inner_->breakpoints();
  b.push_back(inner_->t_end());
  return b;
}

}  // namespace freeflex
