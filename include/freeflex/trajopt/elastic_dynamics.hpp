#pragma once
// The elastic motion inside the maneuver optimizer (docs/theory.md section 11, "Elastic
// modes in the optimal control problem"): the first-order model (eq. 7.1) about the
// zero-order motion, written with the rigid perturbation in body axes so that the mass
// matrix is the constant 𝕄_b of the body at rest, and with commands u1 = 0.
//
//   x1 = [θ1, ξ (m), v1 (2), θ1', ξ' (m)]          4 + 2m entries, q = B ξ
//   B = I (m = n, every elastic coordinate: the first-order model itself), or the first m
//       mass-normalized elastic modes at rest (eq. 4.1), a Galerkin truncation of it
//   v1 = C(θ0)ᵀ R1' (body components of the translational rate perturbation; R1 itself
//        enters no equation, translation invariance, so it is not a state)
//   x1' = [θ1'; q'; a1],   𝕄_b a1 = K_pos(p) [θ1; q] + K_vel(p) [v1; θ1'; q'] + r(p)
//   p = (θ0, θ0', u)                                                            (eq. 11.4)
//
// Every coefficient is linear in the features φ(p) = [1, θ0', θ0'², u_k, u_k cos θ0,
// u_k sin θ0], so x1' = Σ_i φ_i(p) (P_i x1 + c_i) with constant P_i, c_i formed once;
// the derivatives follow from those of φ (at most two nonzero first and three second
// derivatives each). Features whose P_i and c_i vanish (cos and sin terms of body-fixed
// thrusters and torques) are dropped, and with them the θ0 dependence.
//
// Geometric stiffening enters the q rows' stiffness as K − θ0'² (M − G_c) − a_x H_bar
// (a_x = e1ᵀ C0ᵀ R0'', the body-axis acceleration of o), with ModalIntegrals::H_bar and
// G_c (zero until a model fills them); the per-element axial-load term has its place
// marked in the source.
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/trajopt/rigid_dynamics.hpp"

namespace freeflex {

class ElasticDynamics {
 public:
  /// Geometric-stiffening integrals (n x n each); default: the body's ModalIntegrals.
  struct Stiffening {
    Eigen::MatrixXd H_bar, G_c;
  };

  /// Throws std::invalid_argument for a bad actuator list (as RigidDynamics) or, with
  /// `stiffening`, matrices that are not n x n.
  /// `modes`: m, the elastic modes kept (1 <= m <= n), or all_modes (-1: B = I, m = n).
  static constexpr int all_modes = -1;
  ElasticDynamics(const FlexibleBody& body, std::vector<int> actuators, int modes = all_modes);
  ElasticDynamics(const FlexibleBody& body, std::vector<int> actuators, const Stiffening& stiffening,
                  int modes = all_modes);

  int n() const { return m_; }           ///< elastic coordinates in x1 (m)
  int nx() const { return 4 + 2 * m_; }  ///< size of x1
  bool truncated() const { return truncated_; }
  /// q = basis() ξ (body n x m).
  const Eigen::MatrixXd& basis() const { return B_; }
  int nu() const { return nu_; }
  int np() const { return 2 + nu_; }  ///< p = (θ0, θ0', u)
  /// Index in x1 of ξ(0), of ξ'(0).
  int q_index() const { return 1; }
  int q_rate_index() const { return m_ + 4; }
  /// Whether any coefficient depends on θ0 (inertial forces) / on θ0' (always, m > 0).
  bool depends_on_theta() const { return theta_used_; }

  struct Data {
    Eigen::VectorXd f;   ///< x1', from calc() and calc_diff()
    Eigen::MatrixXd Jx;  ///< ∂x1'/∂x1 (nx x nx), from calc_diff()
    Eigen::MatrixXd Jp;  ///< ∂x1'/∂p (nx x np), from calc_diff()
    Eigen::MatrixXd Hpp; ///< Σ λ_i ∂²x1'_i/∂p² (np x np), from calc_hessian()
    Eigen::MatrixXd Hpx; ///< Σ λ_i ∂²x1'_i/∂p∂x1 (np x nx), from calc_hessian()
    Eigen::VectorXd Y;   ///< scratch: P_i x1 + c_i stacked
    Eigen::VectorXd phi; ///< scratch: feature values
  };
  Data create_data() const;

  /// x1' at (θ0, θ0', u, x1).
  void calc(Data& data, double theta, double omega, const Eigen::Ref<const Eigen::VectorXd>& u,
            const Eigen::Ref<const Eigen::VectorXd>& x1) const;
  /// x1' and its first derivatives.
  void calc_diff(Data& data, double theta, double omega, const Eigen::Ref<const Eigen::VectorXd>& u,
                 const Eigen::Ref<const Eigen::VectorXd>& x1) const;
  /// Second derivatives contracted with lambda (nx entries); x1' is linear in x1.
  void calc_hessian(Data& data, double theta, double omega, const Eigen::Ref<const Eigen::VectorXd>& u,
                    const Eigen::Ref<const Eigen::VectorXd>& x1, const Eigen::Ref<const Eigen::VectorXd>& lambda) const;

  /// The elastic modes of the body at rest (eq. 4.1 in body axes) that x1 can hold (m):
  /// frequencies ω_j ascending, and the rows that give the mass-normalized modal
  /// coordinates from ξ, η = modal_rows() ξ (η' likewise from ξ'; the identity when
  /// truncated). E_vib = ½ Σ (η_j'² + ω_j² η_j²), eq. 6.8.
  const Eigen::VectorXd& mode_frequencies() const { return omega_; }
  const Eigen::MatrixXd& modal_rows() const { return modal_rows_; }
  /// Elastic modes that some actuator excites at attitude theta (participation |vᵀ g_k|
  /// above 1e-8 of that actuator's largest), ascending: the switch-time design's choice.
  std::vector<int> excited_modes(double theta) const;
  /// M_c and K of eq. 6.8 in ξ (Bᵀ M_c B and Bᵀ K B, m x m).
  const Eigen::MatrixXd& condensed_mass() const { return M_c_; }
  const Eigen::MatrixXd& stiffness() const { return K_; }
  /// Φ B at the beam's two ends (1 x m each): the tip deflections are Φ q = Φ B ξ.
  const Eigen::RowVectorXd& phi_left() const { return phi_left_; }
  const Eigen::RowVectorXd& phi_right() const { return phi_right_; }

  /// Hessian structure over p (lower triangle, (a, b) with a >= b) and the p entries
  /// that x1' depends on at all.
  const std::vector<std::pair<int, int>>& pp_pattern() const { return pp_pattern_; }
  const std::vector<int>& active_p() const { return active_p_; }

 private:
  enum class Kind { One, Omega, Omega2, U, UCos, USin };
  struct Feature {
    Kind kind;
    int actuator;  // for U, UCos, USin
  };
  void build(const FlexibleBody& body, const Stiffening& stiffening);
  double value(const Feature& f, double c, double s, double omega, const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// First derivatives: up to two (p index, value) pairs; second: up to three (a, b, value), a >= b.
  int first(const Feature& f, double c, double s, double omega, const Eigen::Ref<const Eigen::VectorXd>& u,
            int* idx, double* d) const;
  int second(const Feature& f, double c, double s, const Eigen::Ref<const Eigen::VectorXd>& u, int* ia, int* ib,
             double* d) const;

  int n_ = 0, m_ = 0, nu_ = 0, na_ = 0;  // na_ = 3 + m acceleration rows
  int modes_ = all_modes;
  bool truncated_ = false;
  Eigen::MatrixXd B_;
  std::vector<int> actuators_;
  std::vector<Feature> features_;
  Eigen::MatrixXd P_;  // (F na) x nx, the P_i stacked
  Eigen::VectorXd c_;  // F na
  bool theta_used_ = false;
  std::vector<std::pair<int, int>> pp_pattern_;
  std::vector<int> active_p_;
  Eigen::VectorXd omega_;
  Eigen::MatrixXd modal_rows_, M_c_, K_, V_, Mb_;
  Eigen::MatrixXd G_trig_[3];  // per actuator: body-frame generalized force, A, B, C of A + B cos + C sin (N x nu)
  Eigen::RowVectorXd phi_left_, phi_right_;
};

}  // namespace freeflex
