#pragma once
// Plane rotation helpers shared by the dynamics (docs/theory.md section 1). Private to src/.
#include <cmath>

#include <Eigen/Dense>

namespace freeflex::planar {

/// C(θ) = [[cos θ, -sin θ], [sin θ, cos θ]]
inline Eigen::Matrix2d rot(double a) {
  Eigen::Matrix2d C;
  C << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return C;
}

/// J = [[0, -1], [1, 0]]: dC/dθ = C J, J J = -I
inline const Eigen::Matrix2d& J() {
  static const Eigen::Matrix2d j = (Eigen::Matrix2d() << 0.0, -1.0, 1.0, 0.0).finished();
  return j;
}

}  // namespace freeflex::planar
