#pragma once
// Shape functions of one beam element on [a, b], h = b - a, element coordinate
// xi = (2x - a - b)/h in [-1, 1] (docs/theory.md eq. 2.5). Local DOFs: w_a, w'_a, w_b, w'_b
// (Hermite cubics) and, for order 5, two bubbles whose curvatures in xi are the Legendre
// polynomials P2 and P3: they vanish with their slope at both ends (C¹ across nodes) and
// their curvature is orthogonal to the cubics' (linear) curvature and to each other's.
// Private to src/.
#include <Eigen/Dense>

namespace freeflex::element {

struct Shape {
  Eigen::RowVectorXd N, N1, N2;  // values, d/dx, d2/dx2 of the local shape functions
};

inline Shape shape(double xi, double h, int per) {
  Shape s{Eigen::RowVectorXd(per), Eigen::RowVectorXd(per), Eigen::RowVectorXd(per)};
  const double x2 = xi * xi, d = 2.0 / h, dd = d * d, hh = 0.5 * h;
  // Hermite cubics in xi; the slope functions carry h/2 so that their DOF is dw/dx.
  s.N(0) = (2.0 - 3.0 * xi + xi * x2) / 4.0;
  s.N1(0) = d * (-3.0 + 3.0 * x2) / 4.0;
  s.N2(0) = dd * 1.5 * xi;
  s.N(1) = hh * (1.0 - xi - x2 + xi * x2) / 4.0;
  s.N1(1) = (-1.0 - 2.0 * xi + 3.0 * x2) / 4.0;  // hh * d = 1
  s.N2(1) = d * (3.0 * xi - 1.0) / 2.0;         // hh * dd = d
  s.N(2) = (2.0 + 3.0 * xi - xi * x2) / 4.0;
  s.N1(2) = d * (3.0 - 3.0 * x2) / 4.0;
  s.N2(2) = -dd * 1.5 * xi;
  s.N(3) = hh * (-1.0 - xi + x2 + xi * x2) / 4.0;
  s.N1(3) = (-1.0 + 2.0 * xi + 3.0 * x2) / 4.0;
  s.N2(3) = d * (3.0 * xi + 1.0) / 2.0;
  if (per == 6) {
    const double b = 1.0 - x2;  // bubbles (1 - xi^2)^2 / 8 and xi (1 - xi^2)^2 / 8
    s.N(4) = b * b / 8.0;
    s.N1(4) = d * (xi * x2 - xi) / 2.0;
    s.N2(4) = dd * (3.0 * x2 - 1.0) / 2.0;  // P2
    s.N(5) = xi * b * b / 8.0;
    s.N1(5) = d * (1.0 - 6.0 * x2 + 5.0 * x2 * x2) / 8.0;
    s.N2(5) = dd * (5.0 * xi * x2 - 3.0 * xi) / 2.0;  // P3
  }
  return s;
}

}  // namespace freeflex::element
