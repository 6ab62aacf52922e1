#pragma once
// The paper's admissible functions (docs/theory.md section 2): each side of o, of length
// a_left or a_right, is a cantilever clamped at o. With psi_k the k-th cantilever mode on
// [0, a] (tip value +-2, integral of psi_k^2 equal to a):
//  * equal sides (o at the centre), the paper's pairs
//      phi_{2k-1}(x) = psi_k(|x|)            (symmetric about o)
//      phi_{2k}(x)   = sign(x) psi_k(|x|)    (antisymmetric about o);
//  * unequal sides, one-sided functions (psi_k on one side, zero on the other) taken in
//    ascending order of their wavenumber lambda_k / a_side, so that both sides are
//    resolved alike and a short side gets functions only when its wavenumber is reached
//    (eq. 2.4; the pairs mix a very stiff short-side function into every long-side one).
//    With o at an end (one side of zero length: a cantilever clamped at o) that order
//    gives the other side's cantilever modes in order, phi_k(x) = psi_k(|x|), k = 1..n.
// Either way phi(0) = phi'(0) = 0 and rigid motion lives in (R, theta) alone, and the
// first n functions for n + 1 are the functions for n (nested Ritz spaces).
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/model/shape_basis.hpp"

namespace freeflex {

/// Largest number of admissible functions (NOA) freeflex supports.
inline constexpr int kMaxNoa = 100;

/// k-th root (k >= 1) of 1 + cos(lambda) cosh(lambda) = 0 (clamped-free beam).
double cantilever_root(int k);

/// Value and first two derivatives with respect to z of the k-th cantilever mode
/// psi_k(z) = cosh z - cos z - sigma_k (sinh z - sin z), z = lambda_k xi / a in
/// [0, lambda_k], evaluated without cancellation for any k (docs/theory.md eq. 2.3).
struct CantileverMode {
  double value, d1, d2;
};

/// The constants of one cantilever mode, computed once.
struct CantileverConstants {
  explicit CantileverConstants(int k);
  double lambda;   ///< root of 1 + cos(lambda) cosh(lambda) = 0
  double sigma;    ///< (sinh - sin)/(cosh + cos) at lambda
  double growth;   ///< (1 - sigma) e^lambda, O(1) for every k
  CantileverMode at(double z) const;
};
CantileverMode cantilever_mode(int k, double z);

class AdmissibleBasis : public ShapeBasis {
 public:
  /// n functions on [-a_left, a_right]. One side's length may be zero (o at that end:
  /// the other side's cantilever modes only). Throws std::invalid_argument if n is outside
  /// [1, kMaxNoa], a side's length is negative or not finite, or both are zero.
  AdmissibleBasis(int n, double a_left, double a_right);

  int size() const override { return n_; }
  double a_left() const { return a_left_; }
  double a_right() const { return a_right_; }
  /// True when o is at an end (one side of zero length).
  bool one_sided() const { return a_left_ == 0.0 || a_right_ == 0.0; }
  /// Whether the sides count as equal (relative difference <= 1e-12): the paper's pairs.
  bool symmetric_pairs() const { return symmetric_; }
  /// Largest wavenumber lambda_k / a_side among the functions (sets quadrature density).
  double max_wavenumber() const;
  /// Functions on the left and on the right side of o (pairs count on both).
  int functions_left() const;
  int functions_right() const;

  BasisValues evaluate(double x) const override;
  /// {0}: the curvature of antisymmetric and one-sided functions jumps at o.
  std::vector<double> cuts() const override { return {0.0}; }
  /// 2.5 / max_wavenumber(): 20-point Gauss then resolves products to round-off.
  double max_panel_width() const override { return 2.5 / max_wavenumber(); }
  std::string name() const override { return "paper"; }

 private:
  enum class Shape { Symmetric, Antisymmetric, Left, Right };
  struct Function {
    Shape shape;
    int k;  // cantilever index - 1, into modes_
  };
  int n_;
  double a_left_, a_right_;
  bool symmetric_;
  std::vector<Function> functions_;
  std::vector<CantileverConstants> modes_;  // cantilever indices k = 1..largest used
};

}  // namespace freeflex
