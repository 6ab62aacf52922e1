#pragma once
// Integration variables that leave the elastic oscillation out of what CVODE integrates
// (docs/theory.md section 8). The elastic coordinates are taken to the modes of the
// beam at rest, q = Φ η, and each modal coordinate is written as the quasi-static
// response to the modal force at the start of the piece plus a free oscillation,
//   η_k = ρ_k(t_s)/ω_k² + a_k cos ω_dk τ + b_k sin ω_dk τ,  τ = t - t_s,
// whose amplitudes (a_k, b_k) change only as fast as the modal force departs from its
// value at t_s (and decay with the mode's damping). The rigid coordinates are shifted
// by the rigid motion each elastic mode carries with it, r_s = r + T q (T = M_rr⁻¹ M_rq
// at rest, rotated into the inertial frame), so they too see no elastic oscillation to
// first order. The change is exact: it alters how many steps CVODE takes, never the
// equations. Private to src/ (SimulationOptions::Variables chooses it); its members are
// the callbacks of an integrate() call, which write into the buffers they are handed.
#include <functional>
#include <memory>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex {

class ModalVariables {
 public:
  /// x' = f(t, x) for x = [R, θ, q, R', θ', q'] (size 2(3+n)); false on failure.
  using PhysicalRhs = std::function<bool(const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x,
                                         Eigen::Ref<Eigen::VectorXd> x_dot)>;

  /// For the full model, `frame` is null: the rotation that carries T q into the inertial
  /// frame is the state's own θ. For the first-order model about a rigid trajectory, x is
  /// the perturbation and the rotation is the trajectory's θ0(t).
  ModalVariables(const FlexibleBody& body, PhysicalRhs physical, std::shared_ptr<const RigidTrajectory> frame = {});

  /// The OdeSystem CVODE integrates: y' = f(t, y) with the change of variables set.
  /// It refers to this object, which must outlive the integration.
  OdeSystem system(std::function<std::string()> last_error = {});

  int size() const { return 2 * N_; }
  const Eigen::VectorXd& natural_frequencies() const { return omega_; }
  /// Φ (n x n): q = Φ η, Φᵀ M_c Φ = I with M_c the elastic mass at rest (Schur complement).
  const Eigen::MatrixXd& mode_shapes() const { return Phi_; }

  /// x -> y at the start of a piece, fixing that piece's quasi-static modal force.
  bool enter_piece(const Instant& start, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y);
  /// y -> x within the current piece.
  void to_physical(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> x);
  /// y' = f(t, y).
  bool rhs(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> y_dot);

 private:
  struct Frame {
    double angle, rate, accel;
    bool from_state;
  };
  Frame frame_at(const Instant& at) const;
  /// The frame at `at` (the state's θ, θ' from x for the full model) and the translation
  /// s = C(φ) (T q)_R that the deformation carries, with its rate; Tq_, Tqd_ must be set.
  Frame carried_translation(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Vector2d& s,
                            Eigen::Vector2d& s_dot) const;

  int n_, N_;
  PhysicalRhs physical_;
  std::shared_ptr<const RigidTrajectory> frame_;
  Eigen::MatrixXd Phi_, Phi_inv_;  // q = Φ η, η = Φ⁻¹ q
  Eigen::MatrixXd T_;              // 3 x n: rigid motion carried by q at rest (body frame)
  Eigen::VectorXd omega_, omega2_, sigma_, omega_d_;
  Eigen::VectorXd atol_scale_;
  Frame current_{0.0, 0.0, 0.0, true};  // at the last to_physical
  // the current piece
  double t_s_ = 0.0;
  Eigen::VectorXd rho_s_, eta_static_;
  // scratch
  Eigen::VectorXd x_, x_dot_, cos_, sin_, u_, v_, eta_, eta_dot_, f_, Tq_, Tqd_, Tqdd_;
};

}  // namespace freeflex
