#pragma once
// Continuous Lyapunov equations by the real Schur form (Bartels–Stewart): with
// A = Z T Zᵀ (T quasi upper triangular, 1x1 and 2x2 diagonal blocks), (A + σI)ᵀ X +
// X (A + σI) = C becomes a block-triangular system solved block by block in O(n³), real
// arithmetic throughout. One factorization serves any shift σ, which is
// what the Newton–Kleinman CARE polish (σ = 0) and the TV-LQR Newton preconditioner
// (σ = −1/(2γ), γ changing from step to step) need.
#include <complex>
#include <vector>

#include <Eigen/Dense>

namespace freeflex {

class LyapunovSolver {
 public:
  LyapunovSolver() = default;
  /// Factorizes the real square matrix A (real Schur form). Throws
  /// std::invalid_argument if A is not square or not finite.
  explicit LyapunovSolver(const Eigen::Ref<const Eigen::MatrixXd>& A);
  void factorize(const Eigen::Ref<const Eigen::MatrixXd>& A);

  int size() const { return static_cast<int>(T_.rows()); }
  /// Eigenvalues of A (from the diagonal blocks of T).
  Eigen::VectorXcd eigenvalues() const;

  /// X with (A + σI)ᵀ X + X (A + σI) = C. Returns false if some λ_i + λ_j + 2σ is zero
  /// to round-off relative to ‖A‖: no unique solution.
  bool solve(const Eigen::Ref<const Eigen::MatrixXd>& C, double sigma, Eigen::MatrixXd& X) const;
  /// z with (Aᵀ + μI) z = r; false if Aᵀ + μI is singular to round-off.
  bool solve_transposed(const Eigen::Ref<const Eigen::VectorXd>& r, double mu, Eigen::VectorXd& z) const;

 private:
  Eigen::MatrixXd T_, Z_;
  std::vector<int> start_, size_;  // diagonal blocks of T
  double scale_ = 0.0;             // ‖A‖_F, for the singularity test
  mutable Eigen::MatrixXd work_;
};

/// X with Aᵀ X + X A + C = 0 (A stable gives the unique solution; C symmetric gives X
/// symmetric). Throws std::invalid_argument for mismatched sizes and std::runtime_error
/// when the equation is singular (A and −A share an eigenvalue).
Eigen::MatrixXd solve_lyapunov(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::MatrixXd>& C);

}  // namespace freeflex
