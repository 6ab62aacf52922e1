// Bang-bang rotations: the rigid motion θ0(t) of a switching torque, the residual
// vibration a given set of switch times leaves, and zero-vibration input shapers.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "control/switch_time_model.hpp"
#include "freeflex/control/switch_time.hpp"

namespace freeflex {

using detail::fmt10;

BangBangRotation::BangBangRotation(double I_o, double torque_limit_Nm, std::vector<double> switch_times,
                                   double duration_s)
    : tau_max_(torque_limit_Nm), accel_(torque_limit_Nm / I_o), duration_(duration_s) {
  if (!(I_o > 0.0) || !(torque_limit_Nm > 0.0) || !std::isfinite(I_o) || !std::isfinite(torque_limit_Nm))
    throw std::invalid_argument("bang-bang rotation: I_o and the torque limit must be finite and > 0");
  t_.push_back(0.0);
  for (double s : switch_times) {  // equal times: an interval of zero length
    if (!(s >= t_.back()) || !(s <= duration_s))
      throw std::invalid_argument("bang-bang rotation: switch times must ascend inside [0, " + fmt10(duration_s) +
                                  "], got " + fmt10(s));
    t_.push_back(s);
  }
  if (!(duration_s > 0.0) || !(duration_s >= t_.back()) || !std::isfinite(duration_s))
    throw std::invalid_argument("bang-bang rotation: the duration must follow the last switch, got " + fmt10(duration_s));
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
  detail::validate_actuator(body, actuator, where);
  if (modes < 0) throw std::invalid_argument(where + ": modes must be >= 0");
  const BangBangRotation traj(body.integrals().I_o, torque_limit_Nm, switch_times, duration_s);
  detail::Problem P;
  P.body = &body;
  P.actuator = actuator;
  P.I_o = body.integrals().I_o;
  P.tau = torque_limit_Nm;
  P.a = torque_limit_Nm / P.I_o;
  P.rtol = rtol;
  P.atol = atol;
  P.k = modes;
  const double theta_f = traj.at(Instant{duration_s, duration_s + 1.0}).pos(2);
  P.modes = detail::target_modes(body, actuator, theta_f, modes, where);
  std::vector<double> D;
  double prev = 0.0;
  for (double s : switch_times) D.push_back(s - prev), prev = s;
  D.push_back(duration_s - prev);
  BangBangResidual r;
  r.omega_rad_s = P.modes.omega;
  if (!detail::simulate(P, D, r.x1_end, &r.peak_rate_rad_s)) {
    r.message = P.last_error;
    return r;
  }
  const int N = body.dofs();
  const Eigen::VectorXd eta = P.modes.shapes.transpose() * (P.modes.M0 * r.x1_end.head(N));
  const Eigen::VectorXd eta_d = P.modes.shapes.transpose() * (P.modes.M0 * r.x1_end.tail(N));
  r.energy_J = 0.5 * (eta_d.cwiseAbs2() + P.modes.omega.cwiseAbs2().cwiseProduct(eta.cwiseAbs2()));
  r.rigid_kinetic_peak_J = 0.5 * P.I_o * r.peak_rate_rad_s * r.peak_rate_rad_s;
  r.status = IntegrationStatus::Completed;
  return r;
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
