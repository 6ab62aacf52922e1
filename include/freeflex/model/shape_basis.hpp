#pragma once
// The shape functions of the elastic displacement, u(x, t) = Φ(x) q(t) (docs/theory.md
// sections 2 and 3): the interface every model built on a basis uses (modal integrals,
// loads, mode shapes). Two implementations: the paper's admissible functions
// (AdmissibleBasis, basis.hpp) and the finite-element modes (FiniteElementBasis,
// finite_element_basis.hpp). Every basis satisfies Φ(0) = Φ'(0) = 0 at the reference
// point o, so the rigid coordinates (R, θ) alone carry the rigid motion.
//
// Body coordinate x (m) as everywhere: x = s - s_o, the beam occupies [x_left, x_right].
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace freeflex {

/// Values of all n functions at one body coordinate x.
struct BasisValues {
  Eigen::RowVectorXd phi;    ///< Φ(x), 1 x n
  Eigen::RowVectorXd dphi;   ///< Φ'(x)
  Eigen::RowVectorXd ddphi;  ///< Φ''(x); at a cut point the right-hand limit (left-hand at x_right)
};

class ShapeBasis {
 public:
  virtual ~ShapeBasis() = default;

  /// Number of functions n (the elastic coordinates q).
  virtual int size() const = 0;
  /// Φ, Φ', Φ'' at body coordinate x in [x_left, x_right].
  virtual BasisValues evaluate(double x) const = 0;
  /// Body coordinates, ascending, inside (x_left, x_right), where Φ'' (or a higher
  /// derivative) may jump: quadrature panels must end there. The beam's own
  /// discontinuities (segment junctions) are the beam's to report, not the basis's.
  virtual std::vector<double> cuts() const = 0;
  /// Widest panel between cuts on which the 20-point Gauss rule integrates products of
  /// two functions (or of their derivatives) times a linear weight to round-off; +inf
  /// when any panel between consecutive cuts does (piecewise polynomials).
  virtual double max_panel_width() const = 0;
  /// "paper" or "finite_element", as in design files.
  virtual std::string name() const = 0;

  Eigen::RowVectorXd value(double x) const { return evaluate(x).phi; }
  Eigen::RowVectorXd slope(double x) const { return evaluate(x).dphi; }
  Eigen::RowVectorXd curvature(double x) const { return evaluate(x).ddphi; }
};

}  // namespace freeflex
