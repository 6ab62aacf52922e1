#pragma once
// The discretized flexible body shared by all three models (docs/theory.md section 6):
// modal integrals, the configuration-dependent mass matrix, generalized forces of the
// force elements with their derivatives, and modal damping. The allocation-free forms
// the simulators' right-hand sides use are private to src/ (dynamics/body_kernels.hpp).
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/model/loads.hpp"
#include "freeflex/model/modal_integrals.hpp"

namespace freeflex {

class FlexibleBody {
 public:
  /// On the paper's basis of `noa` admissible functions. `damping_ratios[i]` damps
  /// elastic mode i+1 (modes beyond the list are undamped). `geometric_stiffening`: keep
  /// the foreshortening of the bent beam to second order in q (docs/theory.md section 14:
  /// H_bar, G_c and each force element's H(x_a) are computed); false is the paper's model
  /// (section 6). Throws std::invalid_argument for an element off the beam or a negative
  /// ratio.
  FlexibleBody(const Beam& beam, int noa, std::vector<ForceElement> elements,
               std::vector<double> damping_ratios = {}, bool geometric_stiffening = false);
  /// On the basis of n functions that `basis` chooses (make_basis); throws as above and
  /// as make_basis does.
  FlexibleBody(const Beam& beam, int n, const BasisOptions& basis, std::vector<ForceElement> elements,
               std::vector<double> damping_ratios = {}, bool geometric_stiffening = false);
  /// On a basis of the caller's (any ShapeBasis implementation; e.g. a reduced basis of
  /// combinations of another's functions). Throws as above, and for a null basis.
  FlexibleBody(const Beam& beam, std::shared_ptr<const ShapeBasis> basis, std::vector<ForceElement> elements,
               std::vector<double> damping_ratios = {}, bool geometric_stiffening = false);

  int n() const { return basis_->size(); }       ///< elastic coordinates
  int dofs() const { return 3 + basis_->size(); } ///< z = [Rx, Ry, theta, q]
  const Beam& beam() const { return beam_; }
  const ShapeBasis& basis() const { return *basis_; }
  const ModalIntegrals& integrals() const { return mi_; }
  /// True when the model keeps geometric stiffening (section 14).
  bool geometric_stiffening() const { return stiffening_; }
  const std::vector<ForceElement>& elements() const { return elements_; }
  /// Index of the element called `name`, or -1.
  int element_index(const std::string& name) const;
  /// Body coordinate x of element e.
  double element_x(int e) const { return x_[e]; }

  /// 𝕄(theta, q), eq. 6.1 (eq. 14.5 with geometric stiffening), (3+n) x (3+n).
  Eigen::MatrixXd mass_matrix(double theta, const Eigen::Ref<const Eigen::VectorXd>& q) const;
  /// The same into out (resized; no allocation when it has the size already).
  void mass_matrix_into(double theta, const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::MatrixXd& out) const;

  /// A generalized force and its derivative with respect to (theta, q).
  struct ForceDerivative {
    Eigen::VectorXd value;       ///< [F; M_o; Q], 3+n
    Eigen::MatrixXd derivative;  ///< (3+n) x (1+n)
  };
  /// Generalized force [F; M_o; Q] of element e per unit command at (theta, q), eq. 6.4.
  Eigen::VectorXd element_force(int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q) const;
  /// The same into out (3+n entries).
  void element_force_into(int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                          Eigen::Ref<Eigen::VectorXd> out) const;
  /// The same with its derivative with respect to (theta, q).
  ForceDerivative element_force_derivative(int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q) const;
  /// Sum over elements of commands(e) times element_force.
  Eigen::VectorXd generalized_force(double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                                    const Eigen::Ref<const Eigen::VectorXd>& commands) const;
  /// The same with its derivative with respect to (theta, q).
  ForceDerivative generalized_force_derivative(double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                                               const Eigen::Ref<const Eigen::VectorXd>& commands) const;

  /// Basis values Φ(x_e) and slopes Φ'(x_e) at element e (1 x n).
  const Eigen::RowVectorXd& element_phi(int e) const { return phi_[e]; }
  const Eigen::RowVectorXd& element_slope(int e) const { return dphi_[e]; }
  /// H(x_e) of eq. 14.1 at element e (n x n; empty without geometric stiffening).
  const Eigen::MatrixXd& element_foreshortening(int e) const { return H_[e]; }

  /// Modal damping D (eq. 6.5), (3+n) x (3+n); zero when no ratio is set.
  const Eigen::MatrixXd& damping() const { return D_; }
  bool damped() const { return damped_; }

  /// M_c, the mass seen by q when the rigid momenta are held: the Schur complement of the
  /// rigid block of the mass matrix at rest (eq. 6.8), n x n.
  const Eigen::MatrixXd& condensed_mass() const { return M_condensed_; }
  /// Energy of the elastic motion alone, eq. 6.8: 1/2 q'ᵀ M_c q' + 1/2 qᵀ K q, with M_c
  /// the mass seen by q when the rigid momenta are held (Schur complement).
  double vibration_energy(const Eigen::Ref<const Eigen::VectorXd>& q,
                          const Eigen::Ref<const Eigen::VectorXd>& q_dot) const;

 private:
  Beam beam_;
  std::shared_ptr<const ShapeBasis> basis_;  // immutable: copies of the body share it
  ModalIntegrals mi_;
  std::vector<ForceElement> elements_;
  std::vector<double> x_;
  std::vector<Eigen::RowVectorXd> phi_, dphi_;  // basis and slope at each element
  std::vector<Eigen::MatrixXd> H_;               // H(x_e) (geometric stiffening)
  Eigen::MatrixXd D_, M_condensed_;
  bool damped_ = false;
  bool stiffening_ = false;
};

/// The elastic modes of a body at rest with the rigid momenta held (docs/theory.md
/// section 8): T = M_rr⁻¹ M_rq (the rigid motion each q drags along), the Schur complement
/// M_c = M_qq − M_qr T, and K φ = ω² M_c φ with Φᵀ M_c Φ = I, ω² ascending. Throws
/// std::runtime_error when the eigensolver fails or the lowest ω² is not positive.
struct RestModes {
  Eigen::MatrixXd T;       ///< 3 x n
  Eigen::MatrixXd M_c;     ///< n x n
  Eigen::MatrixXd Phi;     ///< n x n, columns the modes: q = Φ η
  Eigen::VectorXd omega2;  ///< ω², ascending [rad²/s²]
};
RestModes rest_modes(const FlexibleBody& body);

}  // namespace freeflex
