#pragma once
// Modal integrals of the discretized beam (docs/theory.md section 3). With dm the
// distributed mass plus point masses (and the hub at o):
//   m = int dm, S_o = int x dm, I_o = int x^2 dm + hub rotary inertia
//   M = int Phi^T Phi dm, Phi_bar = int Phi dm, Phi_tilde = int x Phi dm,
//   K = int EI Phi''^T Phi'' dx
// for any shape basis (the paper's admissible functions or the finite-element modes).
#include <memory>
#include <string>

#include <Eigen/Dense>

#include "freeflex/enum_names.hpp"
#include "freeflex/model/basis.hpp"
#include "freeflex/model/beam.hpp"
#include "freeflex/model/finite_element_basis.hpp"
#include "freeflex/model/quadrature.hpp"
#include "freeflex/model/shape_basis.hpp"

namespace freeflex {

struct ModalIntegrals {
  double m = 0.0;    ///< total mass [kg]
  double S_o = 0.0;  ///< first moment of mass about o [kg m]
  double I_o = 0.0;  ///< second moment about o, hub rotary inertia included [kg m^2]
  Eigen::MatrixXd M;            ///< n x n elastic mass [kg]
  Eigen::MatrixXd K;            ///< n x n stiffness [N/m]
  Eigen::RowVectorXd Phi_bar;   ///< 1 x n [kg]
  Eigen::RowVectorXd Phi_tilde; ///< 1 x n [kg m]
  /// Geometric stiffening (foreshortening of the bent beam, docs/theory.md): with
  /// H(x) = ∫ between o and x of Phi'^T Phi', H_bar = ∫ sgn(x) H(x) dm (axial force per unit
  /// body-axis acceleration of o) and G_c = ∫ |x| H(x) dm (centrifugal tension per unit
  /// theta'^2). n x n; zero when the model leaves stiffening out.
  Eigen::MatrixXd H_bar;        ///< [kg]
  Eigen::MatrixXd G_c;          ///< [kg m]
  int size() const { return static_cast<int>(M.rows()); }
};

/// The admissible basis of a beam: two cantilevers clamped at o.
AdmissibleBasis make_basis(const Beam& beam, int noa);

/// Which basis a model is built on, and the finite-element basis's settings.
struct BasisOptions {
  enum class Kind { Paper, FiniteElement };
  Kind kind = Kind::Paper;
  FiniteElementOptions finite_element;  ///< used when kind is FiniteElement
};

template <>
struct EnumNames<BasisOptions::Kind> {
  static constexpr const char* what = "basis";
  static constexpr std::array<std::pair<BasisOptions::Kind, const char*>, 2> names{
      {{BasisOptions::Kind::Paper, "paper"}, {BasisOptions::Kind::FiniteElement, "finite_element"}}};
};

/// The basis of n functions that `options` chooses. Throws std::invalid_argument for
/// bad options or n (see AdmissibleBasis, FiniteElementBasis).
std::shared_ptr<const ShapeBasis> make_basis(const Beam& beam, int n, const BasisOptions& options);

/// Quadrature nodes (body x) and weights that integrate products of basis functions (and
/// of their derivatives) times the beam's mass or stiffness exactly to round-off:
/// composite 20-point Gauss-Legendre between the beam's breakpoints and the basis's cuts,
/// panels no wider than the basis's max_panel_width().
GaussRule beam_quadrature(const Beam& beam, const ShapeBasis& basis);

ModalIntegrals modal_integrals(const Beam& beam, const ShapeBasis& basis);

/// Geometric stiffening (docs/theory.md section 14), through the ShapeBasis interface
/// (any basis: Φ(0) = Φ'(0) = 0 for all) and composite Gauss quadrature only:
///   H(x) = ∫ Phi'^T Phi' between o and x                                   (eq. 14.1)
///   H_bar = ∫ sgn(x) H(x) dm = ∫ sgn(ξ) μ(ξ) Phi'^T Phi'(ξ) dξ              (eq. 14.3)
///   G_c   = ∫ |x| H(x) dm    = ∫ σ(ξ) Phi'^T Phi'(ξ) dξ                     (eq. 14.3)
/// with μ(ξ) the mass beyond ξ (away from o) and σ(ξ) = ∫ over that mass of |x| dm; the
/// distributed mass enters through μ and σ (piecewise polynomials), point masses through
/// H at their positions.
struct StiffeningIntegrals {
  Eigen::MatrixXd H_bar;  ///< n x n [kg]
  Eigen::MatrixXd G_c;    ///< n x n [kg m]
};
StiffeningIntegrals stiffening_integrals(const Beam& beam, const ShapeBasis& basis);
/// The modal integrals with H_bar and G_c filled.
ModalIntegrals stiffened_modal_integrals(const Beam& beam, const ShapeBasis& basis);
/// H(x) of eq. 14.1 (n x n, symmetric positive semidefinite) at body coordinate x: the
/// foreshortening of the point at x is h(x) = 1/2 q^T H(x) q.
Eigen::MatrixXd foreshortening_matrix(const Beam& beam, const ShapeBasis& basis, double x);

}  // namespace freeflex
