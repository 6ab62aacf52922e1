#pragma once
// Gauss-Legendre quadrature on composite panels. Units: whatever x carries.
#include <Eigen/Dense>

namespace freeflex {

/// Nodes and weights of the n-point Gauss-Legendre rule on [-1, 1].
struct GaussRule {
  Eigen::VectorXd nodes;
  Eigen::VectorXd weights;
};

/// n-point Gauss-Legendre rule (n >= 1); exact for polynomials of degree 2n-1.
GaussRule gauss_legendre(int n);

/// Composite rule on [a, b]: `panels` equal panels of the n-point rule.
/// Throws std::invalid_argument if b <= a, panels < 1 or n < 1.
GaussRule composite_gauss(double a, double b, int panels, int n);

}  // namespace freeflex
