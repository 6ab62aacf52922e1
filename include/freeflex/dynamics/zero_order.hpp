#pragma once
// Zero-order (rigid) model, eq. 6.3 with q = 0, and the rigid trajectory that the
// first-order model is built about.
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"

namespace freeflex {

/// Rigid motion at one instant: position, rate and acceleration of (Rx, Ry, theta).
struct RigidState {
  Eigen::Vector3d pos = Eigen::Vector3d::Zero();  ///< [Rx, Ry, theta]
  Eigen::Vector3d vel = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc = Eigen::Vector3d::Zero();
};

/// The zero-order equations: 𝕄_rr(θ) [R''; θ''] = [F + θ'² C s0; M_o] at q = 0.
/// State x0 = [Rx, Ry, theta, Rx', Ry', theta'].
class ZeroOrderModel {
 public:
  explicit ZeroOrderModel(const FlexibleBody& body) : body_(body) {}
  const FlexibleBody& body() const { return body_; }
  /// [R''; θ''] at state x0 under element commands.
  Eigen::Vector3d acceleration(const Eigen::Ref<const Eigen::VectorXd>& x0,
                               const Eigen::Ref<const Eigen::VectorXd>& commands) const;
  /// x0' = [x0(3:5); acceleration].
  Eigen::Matrix<double, 6, 1> rhs(const Eigen::Ref<const Eigen::VectorXd>& x0,
                                  const Eigen::Ref<const Eigen::VectorXd>& commands) const;

 private:
  const FlexibleBody& body_;
};

/// A rigid maneuver R0(t), θ0(t) with its first and second derivatives, from a
/// simulation or an optimizer. Accelerations may jump at breakpoints; `at` uses the
/// piece containing Instant::piece_mid.
class RigidTrajectory {
 public:
  virtual ~RigidTrajectory() = default;
  virtual RigidState at(const Instant& when) const = 0;
  virtual double t_begin() const = 0;
  virtual double t_end() const = 0;
  /// Times where the acceleration may jump (pieces of the timeline).
  virtual std::vector<double> breakpoints() const = 0;
  /// Times inside the pieces where the motion's higher derivatives jump (the nodes of a
  /// piecewise interpolant; empty when it is smooth there). The Taylor series of the
  /// perturbation solution do not step across one (docs/theory.md section 8).
  virtual std::vector<double> knots() const { return {}; }
};

/// Samples (t, pos, vel, acc) on each smooth piece, interpolated by quintic Hermite
/// polynomials (position, rate and acceleration matched at both ends of an interval):
/// error O(h^6) in position, O(h^4) in acceleration.
class SampledRigidTrajectory : public RigidTrajectory {
 public:
  struct Piece {
    std::vector<double> t;               ///< ascending, at least two
    std::vector<RigidState> samples;     ///< one per t
  };
  /// Pieces must be in time order, each starting where the previous one ends.
  explicit SampledRigidTrajectory(std::vector<Piece> pieces);
  RigidState at(const Instant& when) const override;
  double t_begin() const override { return pieces_.front().t.front(); }
  double t_end() const override { return pieces_.back().t.back(); }
  std::vector<double> breakpoints() const override;
  /// Every sample time: the interpolant's third derivative jumps there.
  std::vector<double> knots() const override;

 private:
  std::vector<Piece> pieces_;
};

/// A trajectory continued past its end by uniform motion (rate held, acceleration zero):
/// a maneuver that ends at rest stays at rest. The end is a breakpoint.
class ExtendedTrajectory : public RigidTrajectory {
 public:
  ExtendedTrajectory(std::shared_ptr<const RigidTrajectory> inner, double t_end)
      : inner_(std::move(inner)), t_end_(t_end) {}
  RigidState at(const Instant& when) const override;
  double t_begin() const override { return inner_->t_begin(); }
  double t_end() const override { return t_end_; }
  std::vector<double> breakpoints() const override;
  std::vector<double> knots() const override { return inner_->knots(); }

 private:
  std::shared_ptr<const RigidTrajectory> inner_;
  double t_end_;
};

}  // namespace freeflex
