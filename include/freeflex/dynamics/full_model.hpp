#pragma once
// The full nonlinear (hybrid, discretized) model, eq. 6.2: Lagrange's equations of the
// beam with z = [Rx, Ry, theta, q] and state x = [z, z'] (size 2(3+n)).
#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/dynamics/zero_order.hpp"  // RigidState

namespace freeflex {

class FullModel {
 public:
  /// Workspace of one thread of evaluation (make one with create_data()): the result of
  /// rhs() and its scratch. The model itself is const: one model serves any number of
  /// threads, each with its own Data.
  struct Data {
    Eigen::VectorXd x_dot;  ///< x' from the last rhs()
    Eigen::VectorXd G, b, Mq, Kq, Dzd, split;  // scratch
    Eigen::VectorXd Hq, Hqd, Gq, Wv;    // scratch of the stiffened model
    Eigen::VectorXd xq_dot;             ///< [q', q''] from the last prescribed_rhs()
    Eigen::VectorXd zd_full;            // scratch of prescribed_rhs()
  };

  /// Factors the body-frame mass matrix at rest once (see rhs).
  explicit FullModel(const FlexibleBody& body);
  const FlexibleBody& body() const { return body_; }
  /// 𝕄_b(0)⁻¹, the body-frame mass matrix at rest inverted once (see rhs).
  const Eigen::MatrixXd& rest_inverse() const { return rest_inverse_; }
  /// The same with its columns padded with zero rows to a multiple of 4 (whole vectors for
  /// the right-hand side's kernels).
  const Eigen::MatrixXd& rest_inverse_padded() const { return rest_inverse_padded_; }
  int state_size() const { return 2 * body_.dofs(); }
  Data create_data() const;

  /// Residual of eq. 6.2, 𝕄 z'' + h(z, z') + [0; 0; K q] + D z' - G(z, u): zero on the motion.
  Eigen::VectorXd residual(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::Ref<const Eigen::VectorXd>& z_dot,
                           const Eigen::Ref<const Eigen::VectorXd>& z_ddot,
                           const Eigen::Ref<const Eigen::VectorXd>& commands) const;

  /// x' for x = [z, z'] under element commands u, into data.x_dot. Returns false if the
  /// mass matrix is singular or indefinite (the state has left the model's validity).
  ///
  /// 𝕄(θ, q) = T 𝕄_b(q) Tᵀ with T = blockdiag(C(θ), 1, I) and the body-frame 𝕄_b(q),
  /// which differs from 𝕄_b(0) only in the (x, θ) entries (−Φ̄ q) and the (θ, θ) entry
  /// (+ qᵀ M q): a symmetric rank-two change. So z'' comes from the inverse of 𝕄_b(0),
  /// formed at construction, and a 2 x 2 Woodbury correction instead of a new
  /// factorization at every call. With geometric stiffening (eq. 14.5-14.6) the change
  /// also touches the (x, q) and (y, θ) entries: a rank-four update, 4 x 4 Woodbury.
  bool rhs(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
           const Eigen::Ref<const Eigen::VectorXd>& commands) const;

  /// Prescribed rigid motion (docs/theory.md eq. 14.10): (R, θ) follow `rigid` (its
  /// position, rate and acceleration at this instant) and only the q rows of eq. 6.2 /
  /// 14.6 remain, M q'' = Q − Bᵀ Cᵀ R'' − Φ̃ᵀ θ'' + θ'² (M − G_c) q − K q − D_q z'.
  /// xq = [q, q'] (2n); [q', q''] into data.xq_dot. Always true (M is constant).
  bool prescribed_rhs(Data& data, const RigidState& rigid, const Eigen::Ref<const Eigen::VectorXd>& xq,
                      const Eigen::Ref<const Eigen::VectorXd>& commands) const;
  /// The generalized force [F; M_o] that holds (R, θ) on a prescribed motion: the rigid
  /// rows of the residual at (z, z', z'') with the loads (eq. 14.11).
  Eigen::Vector3d constraint_force(const Eigen::Ref<const Eigen::VectorXd>& z,
                                   const Eigen::Ref<const Eigen::VectorXd>& z_dot,
                                   const Eigen::Ref<const Eigen::VectorXd>& z_ddot,
                                   const Eigen::Ref<const Eigen::VectorXd>& commands) const;

  /// Invariants with no load (eq. 6.7): T + V, linear momentum, angular momentum about
  /// the inertial origin.
  double energy(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  Eigen::Vector2d linear_momentum(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  double angular_momentum(const Eigen::Ref<const Eigen::VectorXd>& x) const;

 private:
  /// h(z, z') + [0; 0; K q] + D z': everything in eq. 6.2 but inertia and loads (the
  /// reference form for residual(); rhs writes the same terms out in body axes).
  /// `Mq` is scratch of size n (receives M q).
  void bias(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::Ref<const Eigen::VectorXd>& z_dot,
            Eigen::Ref<Eigen::VectorXd> out, Eigen::Ref<Eigen::VectorXd> Mq) const;
  /// rhs() of the stiffened model (eq. 14.6).
  bool rhs_stiffened(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                     const Eigen::Ref<const Eigen::VectorXd>& commands) const;
  const FlexibleBody& body_;
  Eigen::MatrixXd rest_inverse_;         ///< 𝕄_b(0)⁻¹
  Eigen::MatrixXd rest_inverse_padded_;  ///< the same, its columns padded with zeros to a multiple of 4 rows
  Eigen::MatrixXd mq_inverse_;           ///< M⁻¹ (prescribed motion)
};

}  // namespace freeflex
