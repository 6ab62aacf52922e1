#pragma once
// The discretized flexible body shared by all three models (docs/theory.md section 6):
// modal integrals, the configuration-dependent mass matrix, generalized forces of the
// force elements with their derivatives, and modal damping.
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/model/loads.hpp"
#include "freeflex/model/modal_integrals.hpp"

namespace freeflex {

class FlexibleBody {
 public:
  /// `damping_ratios[i]` damps elastic mode i+1 (modes beyond the list are undamped).
  /// Throws std::invalid_argument for an element off the beam or a negative ratio.
  FlexibleBody(const Beam& beam, int noa, std::vector<ForceElement> elements,
               std::vector<double> damping_ratios = {});

  int n() const { return basis_.size(); }       ///< elastic coordinates
  int dofs() const { return 3 + basis_.size(); } ///< z = [Rx, Ry, theta, q]
  const Beam& beam() const { return beam_; }
  const AdmissibleBasis& basis() const { return basis_; }
  const ModalIntegrals& integrals() const { return mi_; }
  const std::vector<ForceElement>& elements() const { return elements_; }
  /// Index of the element called `name`, or -1.
  int element_index(const std::string& name) const;
  /// Body coordinate x of element e.
  double element_x(int e) const { return x_[e]; }

  /// 𝕄(theta, q), eq. 6.1, (3+n) x (3+n).
  void mass_matrix(double theta, const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Ref<Eigen::MatrixXd> out) const;

  /// Generalized force [F; M_o; Q] of element e per unit command at (theta, q), eq. 6.4;
  /// if `d` is given it receives the derivative with respect to (theta, q): (3+n) x (1+n).
  void element_force(int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                     Eigen::Ref<Eigen::VectorXd> g, Eigen::MatrixXd* d = nullptr) const;
  /// Sum over elements of commands(e) times element_force (and its derivative).
  void generalized_force(double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                         const Eigen::Ref<const Eigen::VectorXd>& commands, Eigen::Ref<Eigen::VectorXd> G,
                         Eigen::MatrixXd* d = nullptr) const;

  /// Adds scale times the generalized force of element e at (theta, q) to G and, if dG is
  /// given, scale times its derivative along (d_theta, d_q) to dG (d_q null: zero).
  /// The allocation-free path of the simulators; element_force is the reference.
  void add_element_force(int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q, double scale,
                         Eigen::Ref<Eigen::VectorXd> G, double d_theta = 0.0, const Eigen::VectorXd* d_q = nullptr,
                         Eigen::VectorXd* dG = nullptr) const;

  /// Modal damping D (eq. 6.5), (3+n) x (3+n); zero when no ratio is set.
  const Eigen::MatrixXd& damping() const { return D_; }
  bool damped() const { return damped_; }

  /// Energy of the elastic motion alone, eq. 6.8: 1/2 q'ᵀ M_c q' + 1/2 qᵀ K q, with M_c
  /// the mass seen by q when the rigid momenta are held (Schur complement).
  double vibration_energy(const Eigen::Ref<const Eigen::VectorXd>& q,
                          const Eigen::Ref<const Eigen::VectorXd>& q_dot) const;

 private:
  Beam beam_;
  AdmissibleBasis basis_;
  ModalIntegrals mi_;
  std::vector<ForceElement> elements_;
  std::vector<double> x_;
  std::vector<Eigen::RowVectorXd> phi_, dphi_;  // basis and slope at each element
  Eigen::MatrixXd D_, M_condensed_;
  bool damped_ = false;
};

}  // namespace freeflex
