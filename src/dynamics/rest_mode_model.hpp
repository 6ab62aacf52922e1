#pragma once
// The full nonlinear model (eq. 6.2) with its elastic coordinates taken to the modes of
// the body at rest, q = Ψ η (SimulationOptions::Variables::RestModes; docs/theory.md
// section 8, "Rest-mode coordinates"). The same equations as FullModel, whose state
// x = [R, θ, q, R', θ', q'] maps to y = [R, θ, η, R', θ', η'] one to one; only the
// arithmetic is cheaper. With Ψᵀ M_c Ψ = μ I and Ψᵀ K Ψ = μ Λ (rest_modes' modes scaled
// by √μ, μ the mean diagonal of M, so that η is of the size of q and the integrator's
// tolerances mean the same in both) the body-frame mass matrix at rest becomes
//
//     𝕄_η(0) = [[A, B], [Bᵀ, μ I + Bᵀ A⁻¹ B]],   A = 𝕄_rr (3 x 3), B = 𝕄_rq Ψ (3 x n),
//
// whose inverse is [[A⁻¹ + A⁻¹ B Bᵀ A⁻¹ / μ, −A⁻¹ B / μ], [−Bᵀ A⁻¹ / μ, I / μ]] (the Schur
// complement of A is μ I): y = 𝕄_η(0)⁻¹ g is u = A⁻¹ g_r, y_η = (g_η − Bᵀ u) / μ,
// y_r = u − A⁻¹ B y_η; and Ψᵀ M Ψ = μ I + Bᵀ A⁻¹ B, η = Ψᵀ M_c q / μ. So M q, K q and the
// solve with 𝕄_b(0), dense n x n and (3+n) x (3+n) products in physical coordinates,
// become a few products with the 3 x n matrix B: the right-hand side's cost grows as n,
// not n². With geometric stiffening (eq. 14.5-14.6) three dense products remain, H̄ q,
// H̄ q' and G_c q in these coordinates, against seven in physical ones. Private to src/.
#include <vector>

#include <Eigen/Dense>

#include "dynamics/body_kernels.hpp"
#include "freeflex/dynamics/flexible_body.hpp"

namespace freeflex::detail {

class RestModeModel {
 public:
  /// Workspace of one thread of evaluation: y' of the last rhs() and scratch.
  struct Data {
    Eigen::VectorXd x_dot, G, g, Dzd;  ///< x_dot: y' (these coordinates) from the last rhs(), as FullModel::Data
    Eigen::VectorXd Hq, Hqd, Mq, Wv, v;         // scratch of the stiffened model
    Eigen::Matrix<double, Eigen::Dynamic, 4> WU;  // its Woodbury columns
  };

  /// Throws std::runtime_error when the modes at rest cannot be computed.
  /// `dense_damping` (tests): apply the damping as the full matrix even where it is diagonal.
  explicit RestModeModel(const FlexibleBody& body, bool dense_damping = false);
  Data create_data() const;
  /// Ψ: q = Ψ η (the columns are the modes, Ψᵀ M_c Ψ = μ I).
  const Eigen::MatrixXd& modes() const { return Psi_; }

  /// y from x = [R, θ, q, R', θ', q'] (η = Ψᵀ M_c q / μ), and x from y.
  Eigen::VectorXd to_rest_modes(const Eigen::Ref<const Eigen::VectorXd>& x) const;
  void to_physical(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> x) const;

  /// y' for y under element commands u, into data.x_dot; false where the mass matrix is
  /// not positive definite, or with geometric stiffening near singular (as FullModel::rhs).
  bool rhs(Data& data, const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& commands) const;

  /// The generalized force in these coordinates, [F (inertial axes); M_o; Ψᵀ Q], into G
  /// (3+n). The power ż·G is the same number in either coordinates.
  void generalized_force(double theta, const Eigen::Ref<const Eigen::VectorXd>& eta,
                         const Eigen::Ref<const Eigen::VectorXd>& commands, Eigen::Ref<Eigen::VectorXd> G) const;
  /// The modal damping in these coordinates, Sᵀ D S with S = blockdiag(I₃, Ψ).
  const Eigen::MatrixXd& damping() const { return D_; }
  /// ż_yᵀ D ż_y for the rates ż_y = [R', θ', η'] (the damping's power, the same in either
  /// coordinates): n products where the damping is diagonal in the modes, as the modal one is.
  double damping_power(const Eigen::Ref<const Eigen::VectorXd>& rates) const;

 private:
  const FlexibleBody& body_;
  int n_;
  Eigen::MatrixXd Psi_;          ///< q = Ψ η
  Eigen::MatrixXd Psi_inverse_;  ///< Ψ⁻¹ = Ψᵀ M_c / μ
  double mu_;                    ///< Ψᵀ M_c Ψ = μ I: the mean diagonal of M
  Eigen::VectorXd L_;            ///< μ ω², the diagonal of Ψᵀ K Ψ
  Eigen::Matrix3d A_inverse_;    ///< 𝕄_rr⁻¹ at rest
  /// The y and θ rows of B = 𝕄_rq Ψ, Φ̄ Ψ and Φ̃ Ψ (its x row is zero: 𝕄_rq = [0; Φ̄; Φ̃])
  Eigen::VectorXd B_y_, B_theta_;
  Eigen::VectorXd W_x_, W_y_, W_theta_;  ///< the x, y and θ columns of 𝕄_η(0)⁻¹ (Woodbury)
  Eigen::MatrixXd H_, G_c_;              ///< Ψᵀ H̄ Ψ and Ψᵀ G_c Ψ (geometric stiffening only)
  Eigen::MatrixXd D_;              ///< damping in these coordinates (empty when undamped)
  Eigen::VectorXd damping_diagonal_;  ///< its elastic diagonal when it is diagonal (the modal damping is)
  ElementRows rows_;               ///< Φ(x_e) Ψ, Φ'(x_e) Ψ
  double S_o_;

  /// y = 𝕄_η(0)⁻¹ g by the block inverse.
  void rest_solve(const Eigen::Ref<const Eigen::VectorXd>& g, Eigen::Ref<Eigen::VectorXd> y) const;
  /// rhs() with geometric stiffening (FullModel::rhs_stiffened in these coordinates).
  bool rhs_stiffened(Data& data, const Eigen::Ref<const Eigen::VectorXd>& y,
                     const Eigen::Ref<const Eigen::VectorXd>& commands) const;
  friend bool rest_mode_rhs(const RestModeModel& m, Data& d, const double* x,
                            const Eigen::Ref<const Eigen::VectorXd>& commands);
};

}  // namespace freeflex::detail
