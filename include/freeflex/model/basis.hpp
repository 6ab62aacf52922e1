#pragma once
// The paper's admissible functions (docs/theory.md section 2): each half of the beam,
// of length a_left or a_right, is a cantilever clamped at o. With psi_k the k-th
// cantilever mode on [0, a] (tip value +-2, integral of psi_k^2 equal to a),
//   phi_{2k-1}(x) = psi_k(|x|)            (symmetric about o)
//   phi_{2k}(x)   = sign(x) psi_k(|x|)    (antisymmetric about o)
// so phi(0) = phi'(0) = 0 and rigid motion lives in (R, theta) alone. With o at an end of
// the beam (one half of zero length: a cantilever clamped at o), the functions are the
// other half's cantilever modes in order, phi_k(x) = psi_k(|x|), k = 1..n.
#include <vector>

#include <Eigen/Dense>

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

/// Values of all n functions at one body coordinate x.
struct BasisValues {
  Eigen::RowVectorXd phi;    ///< Phi(x), 1 x n
  Eigen::RowVectorXd dphi;   ///< Phi'(x)
  Eigen::RowVectorXd ddphi;  ///< Phi''(x); at x = 0 the right-hand limit
};

class AdmissibleBasis {
 public:
  /// n functions on [-a_left, a_right]. One half-length may be zero (o at that end: the
  /// other half's cantilever modes only). Throws std::invalid_argument if n is outside
  /// [1, kMaxNoa], a half-length is negative or not finite, or both are zero.
  AdmissibleBasis(int n, double a_left, double a_right);

  int size() const { return n_; }
  double a_left() const { return a_left_; }
  double a_right() const { return a_right_; }
  /// True when o is at an end (one half of zero length).
  bool one_sided() const { return a_left_ == 0.0 || a_right_ == 0.0; }
  /// Largest wavenumber lambda_k / a over both halves (sets quadrature density).
  double max_wavenumber() const;

  BasisValues evaluate(double x) const;
  Eigen::RowVectorXd value(double x) const { return evaluate(x).phi; }
  Eigen::RowVectorXd slope(double x) const { return evaluate(x).dphi; }
  Eigen::RowVectorXd curvature(double x) const { return evaluate(x).ddphi; }

 private:
  int n_;
  double a_left_, a_right_;
  std::vector<CantileverConstants> modes_;  // one per cantilever index k = 1..ceil(n/2) (1..n one-sided)
};

}  // namespace freeflex
