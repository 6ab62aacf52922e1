#pragma once
// Prescribed rigid motion (docs/theory.md section 14, eq. 14.10): the reference frame's motion
// R(t), θ(t) is given with its first two derivatives instead of being driven by loads,
// and the simulations compute the elastic response to it with the full and the
// first-order models (the q rows of eq. 6.2 / 7.1 alone). A beam clamped at o to a hub
// whose rotation is prescribed is a cantilever appendage (o at an end of the beam).
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/sim/simulate.hpp"

namespace freeflex {

/// The prescribed motion of one coordinate (Rx, Ry of the hub centre in m, or θ in rad)
/// with its rate and acceleration.
class MotionProfile {
 public:
  enum class Kind {
    Rest,    ///< zero for all t
    SpinUp,  ///< smooth ramp of the rate from 0 to `final_rate` over `ramp_time` (Kane, Ryan and Banerjee):
             ///< a'' = (Ω/Ts)(1 − cos(2πt/Ts)) for t < Ts, then a' = Ω (rate, acceleration and jerk continuous)
    Table,   ///< samples of value, rate and acceleration; quintic Hermite between them (C², value
             ///< O(h⁶)); after the last sample the rate is held (acceleration zero)
  };
  MotionProfile() = default;
  /// Throws std::invalid_argument unless ramp_time > 0 and both are finite.
  static MotionProfile spin_up(double final_rate, double ramp_time);
  /// Throws std::invalid_argument unless times start at 0, ascend strictly, and the four
  /// arrays have the same size (>= 2) with finite entries.
  static MotionProfile table(std::vector<double> times, std::vector<double> values, std::vector<double> rates,
                             std::vector<double> accelerations);

  Kind kind() const { return kind_; }
  /// [value, rate, acceleration] at t >= 0.
  Eigen::Vector3d at(double t) const;
  /// Times where a derivative of order <= 3 may jump (the ramp's end, a table's end).
  std::vector<double> breakpoints() const;
  /// The largest |rate| over [0, t_end] (sampled at the table's knots, exact for the ramp).
  double peak_rate(double t_end) const;

 private:
  Kind kind_ = Kind::Rest;
  double rate_ = 0.0, ramp_ = 0.0;
  std::vector<double> t_, v_, r_, a_;
};

/// R(t) = [x(t), y(t)] + r C(θ(t)) e1 and θ(t): the hub centre follows (x, y), o sits at
/// `hub_radius` from it along the body x axis (0: o on the axis of rotation).
class PrescribedMotion : public RigidTrajectory {
 public:
  PrescribedMotion(MotionProfile x, MotionProfile y, MotionProfile theta, double hub_radius = 0.0);
  RigidState at(const Instant& when) const override;
  double t_begin() const override { return 0.0; }
  double t_end() const override { return 1e300; }
  std::vector<double> breakpoints() const override;
  const MotionProfile& theta() const { return theta_; }

 private:
  MotionProfile x_, y_, theta_;
  double r_;
};

/// The elastic response to a prescribed motion: the full model (FullModel::prescribed_rhs)
/// or the first-order model about the motion (FirstOrderModel::prescribed_rhs), from rest
/// (q = q' = 0). z and z_dot hold the prescribed (R, θ) and the computed q; for the full
/// model work_J holds the work done by loads, damping and the constraint that holds the
/// motion (energy balance). A deflection beyond options.max_deflection_ratio times the
/// beam's length ends the run with status out_of_range.
SimulationResult simulate_prescribed(const FlexibleBody& body, const Excitation& excitation,
                                     const PrescribedMotion& motion, const SimulationOptions& options,
                                     bool first_order);

template <>
struct EnumNames<MotionProfile::Kind> {
  static constexpr const char* what = "motion profile type";
  static constexpr std::array<std::pair<MotionProfile::Kind, const char*>, 3> names{
      {{MotionProfile::Kind::Rest, "rest"}, {MotionProfile::Kind::SpinUp, "spin_up"}, {MotionProfile::Kind::Table, "table"}}};
};

}  // namespace freeflex
