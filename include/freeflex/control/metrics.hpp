#pragma once
// Figures of merit of a response (any model): residual vibration energy, tip deflection
// and its settling, rigid errors at the end and control effort. SI units.
#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"

namespace freeflex {

struct MetricTargets {
  Eigen::Vector2d R_target = Eigen::Vector2d::Zero();  ///< wanted final position of o [m]
  double theta_target = 0.0;                           ///< wanted final attitude [rad]
  double energy_window_s = 1.0;  ///< averaging window at the end for mean_vibration_energy_J [s], > 0
};

struct ResponseMetrics {
  double residual_vibration_energy_J = 0.0;  ///< FlexibleBody::vibration_energy at the last time (eq. 6.8)
  /// Time average of the vibration energy over the last energy_window_s (the whole run if
  /// shorter; trapezoid rule). Where the full model keeps trading energy between the
  /// elastic and the rigid motion, the value at one instant swings (0.10-0.28 J on the
  /// paper's moment pulse) and moves with round-off; this average does not.
  double mean_vibration_energy_J = 0.0;
  double peak_tip_deflection_m = 0.0;        ///< max over time and both ends of |Φ(x_end) q|
  /// Last time |tip deflection| (the larger end) exceeds 1% of its peak; the response
  /// has settled from then on if `settled`, otherwise the last sample still exceeds it.
  double tip_settling_time_s = 0.0;
  bool settled = true;
  double final_position_error_m = 0.0;   ///< |R(t_end) − R_target|
  double final_attitude_error_rad = 0.0; ///< |θ(t_end) − θ_target|
  double control_effort = 0.0;           ///< ∫ uᵀu dt by the trapezoid rule [N² s]
  double peak_command = 0.0;             ///< max |u|
};

/// Metrics of the samples (t, z, z_dot) with z = [Rx, Ry, θ, q] rows and optional
/// commands (one row per time; zero columns: no effort). Throws std::invalid_argument
/// if sizes disagree with the body or with each other, or fewer than one sample.
ResponseMetrics response_metrics(const FlexibleBody& body, const Eigen::Ref<const Eigen::VectorXd>& t,
                                 const Eigen::Ref<const Eigen::MatrixXd>& z,
                                 const Eigen::Ref<const Eigen::MatrixXd>& z_dot,
                                 const Eigen::Ref<const Eigen::MatrixXd>& commands,
                                 const MetricTargets& targets = {});

}  // namespace freeflex
