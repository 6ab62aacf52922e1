#pragma once
// The continuous trajectory that a collocation solution stands for.
//   states:   cubic Hermite between knots through x_k, x_{k+1} with slopes f(x_k, u_k),
//             f(x_{k+1}, u_{k+1}); for Hermite–Simpson this cubic passes through the
//             midpoint state and has slope f_c there (the defects say exactly that)
//   controls: piecewise linear (trapezoidal) or piecewise quadratic through knot,
//             midpoint, knot (Hermite–Simpson)
//   RigidState::acc = f(x(t), u(t))[3:5], the zero-order model at the interpolated
//             state and control.
// With the elastic part (trajopt/maneuver_dynamics.hpp) the states hold x1 too; the
// RigidTrajectory is the rigid part x0.
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/trajopt/problem.hpp"
#include "freeflex/trajopt/maneuver_dynamics.hpp"

namespace freeflex {

class CollocationTrajectory : public RigidTrajectory {
 public:
  /// t: N+1 ascending knot times; x: (N+1) x nx; u: (N+1) x nu; u_mid: N x nu, required
  /// for the Hermite–Simpson forms and ignored otherwise. Throws std::invalid_argument on sizes.
  CollocationTrajectory(ManeuverDynamics dynamics, Transcription transcription, Eigen::VectorXd t, Eigen::MatrixXd x,
                        Eigen::MatrixXd u, Eigen::MatrixXd u_mid = Eigen::MatrixXd());

  /// Rigid state at `when`, the interval chosen by when.piece_mid; t clamped to the span.
  RigidState at(const Instant& when) const override;
  double t_begin() const override { return t_(0); }
  double t_end() const override { return t_(t_.size() - 1); }
  /// Interior knots: the control and the acceleration may kink there.
  std::vector<double> breakpoints() const override;

  /// Controls u(t); zero outside [t_begin, t_end] (like a TimeProfile).
  Eigen::VectorXd control_at(double t) const;
  Eigen::VectorXd control_at(const Instant& when) const;
  /// Rigid state x0(t) from the interpolant; t clamped to the span.
  Eigen::Matrix<double, 6, 1> state_at(double t) const;
  Eigen::Matrix<double, 6, 1> state_at(const Instant& when) const;
  /// The whole state x(t) (nx entries: x0, then x1 with the elastic part).
  Eigen::VectorXd full_state_at(const Instant& when) const;

  /// Local error estimate per interval: max_i ∫_k |x_i'(t) − f_i(x(t), u(t))| dt
  /// (5-point Gauss–Legendre), the quantity mesh refinement drives below its tolerance.
  Eigen::VectorXd interval_errors() const;

  const ManeuverDynamics& dynamics() const { return dyn_; }
  Transcription transcription() const { return tr_; }
  int intervals() const { return static_cast<int>(t_.size()) - 1; }
  const Eigen::VectorXd& knot_times() const { return t_; }
  const Eigen::MatrixXd& knot_states() const { return x_; }  ///< (N+1) x nx
  const Eigen::MatrixXd& knot_controls() const { return u_; }
  const Eigen::MatrixXd& mid_controls() const { return u_mid_; }

 private:
  int interval_of(double t) const;
  Eigen::VectorXd state_in(int k, double t, Eigen::VectorXd* rate) const;
  Eigen::VectorXd control_in(int k, double t) const;

  ManeuverDynamics dyn_;
  Transcription tr_;
  Eigen::VectorXd t_;
  Eigen::MatrixXd x_, u_, u_mid_, f_;  // f_: (N+1) x nx, f at the knots
};

}  // namespace freeflex
