#pragma once
// Factor-once solvers of continuous Lyapunov equations, private to src/. By the real
// Schur form (Bartels–Stewart): with A = Z T Zᵀ (T quasi upper triangular, 1x1 and 2x2
// diagonal blocks), (A + σI)ᵀ X + X (A + σI) = C becomes a block-triangular system solved
// block by block in O(n³), real arithmetic throughout. One factorization serves any
// shift σ, which is what the Newton–Kleinman CARE polish (σ = 0) and the TV-LQR Newton preconditioner
// (σ = −1/(2γ), γ changing from step to step) need. Their solve() methods write into the
// caller's matrices: they run in the TV-LQR's inner loop, where an allocation per call
// would cost more than the solve.
#include <complex>
#include <vector>

#include <Eigen/Dense>

namespace freeflex {

namespace detail {
/// C = A B for n x n column-major matrices stored contiguously (leading dimension n).
/// With `upper`, only C's upper triangle (i <= j) is guaranteed; entries below it may be
/// written too. The Newton solves and the Riccati right-hand side of the TV-LQR spend
/// most of their time here at n = 18..46, where Eigen's general product pays its
/// packing overhead: on CPUs with AVX2/FMA a register-blocked kernel (8 x 4 blocks,
/// measured 0.48 vs 0.85 µs at n = 18, 5.9 vs 11.8 µs at n = 46) is used, else Eigen.
void small_gemm(int n, const double* A, const double* B, double* C, bool upper);
}  // namespace detail

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

/// The same equations through a real block diagonalization A = V D V⁻¹: D holds the 1x1
/// and 2x2 diagonal blocks of the real Schur form T = Qᵀ A Q, and V = Q Y where the unit
/// upper triangular Y (T Y = Y D) decouples the blocks by small Sylvester solves. With
/// W = Vᵀ X V, (D + σ)ᵀ W + W (D + σ) = Vᵀ C V splits into independent block equations
/// of at most 2x2 unknowns, each solved in closed form: a 2x2 block is a I + N with N
/// trace-free, N² = −det(N) I, so X ↦ c X + N_Iᵀ X + X N_J is inverted by
/// (c − N_Iᵀ· − ·N_J)(s + 2 N_Iᵀ·N_J) / (s² − 4 d_I d_J), s = c² + d_I + d_J, d = det N.
/// No block is brought to the standard form [[a, b], [−b, a]]: for a near-defective
/// pair, as the uncontrolled double integrator of a free-floating body gives, that
/// rescaling alone has κ ~ 1e6; when the Schur form splits such a pair into two close
/// real eigenvalues, they are kept together as one 2x2 block for the same reason. A
/// solve is then four dense n x n products (three for symmetric C) and O(n²) scalar
/// work, against the Schur solver's two products, a block back substitution of ~n³
/// more and n²/4 small LU solves: measured 2.0 vs 12.3 µs at n = 18, 22 vs 131 µs at
/// n = 46 (symmetric C, AVX2), for a factorization ~15% dearer than the Schur form
/// alone. The price is accuracy: errors grow like κ(V) ε, so factorize() refuses A whose
/// blocks are ill separated (κ(V) large), and the caller falls back to LyapunovSolver.
class ModalLyapunovSolver {
 public:
  /// Block-diagonalizes A (square, finite, else std::invalid_argument). Returns false and
  /// leaves the solver unusable when the Schur decomposition fails or κ₁(V) =
  /// ‖V‖₁‖V⁻¹‖₁ (columns balanced block by block) exceeds max_condition. With `sort`, the
  /// real eigenvalues are first moved to the end of the Schur form in ascending order, so
  /// that a near-defective pair the Schur form left apart becomes adjacent and is kept as
  /// one block (the exponential integrator needs a well-conditioned V at every step; the
  /// Newton solves fall back to the Schur solver instead).
  bool factorize(const Eigen::Ref<const Eigen::MatrixXd>& A, double max_condition, bool sort = false);

  bool ok() const { return ok_; }
  int size() const { return static_cast<int>(V_.rows()); }
  double condition() const { return condition_; }  ///< κ₁(V) of the last factorize()
  /// Eigenvalues of A (from the blocks of D).
  Eigen::VectorXcd eigenvalues() const;

  /// As LyapunovSolver::solve. C need not be symmetric. Returns false when not ok() or
  /// some λ_i + λ_j + 2σ is zero to round-off relative to ‖A‖.
  bool solve(const Eigen::Ref<const Eigen::MatrixXd>& C, double sigma, Eigen::MatrixXd& X) const;
  /// The same for symmetric C: W and X are symmetric, so half of the block equations and
  /// of the last product of each congruence are skipped (~25% less work). X is returned
  /// symmetric.
  bool solve_symmetric(const Eigen::Ref<const Eigen::MatrixXd>& C, double sigma, Eigen::MatrixXd& X) const;
  /// As LyapunovSolver::solve_transposed.
  bool solve_transposed(const Eigen::Ref<const Eigen::VectorXd>& r, double mu, Eigen::VectorXd& z) const;

  /// The form itself (valid when ok()), for the exponential integrator of the TV-LQR:
  /// A = V D V⁻¹ with D's diagonal blocks below.
  struct Block {
    int start, size;
    double mid;              // the block is mid·I + N, N trace-free (zero for 1x1)
    double n00, n01, n10;    // N = [[n00, n01], [n10, −n00]]
    double det, beta;        // det N; sqrt(det N) when > 0 (complex pair mid ± iβ), else −1
  };
  const std::vector<Block>& blocks() const { return blocks_; }
  const Eigen::MatrixXd& V() const { return V_; }
  const Eigen::MatrixXd& Vinv() const { return U_; }
  const Eigen::MatrixXd& Vt() const { return Vt_; }
  const Eigen::MatrixXd& Vinv_t() const { return Ut_; }

 private:
  /// W ← solution of D_Iᵀ W + W D_J + 2σ W = W block by block (blocks I <= J only when
  /// `upper`); false if some block equation is singular.
  bool solve_blocks(Eigen::MatrixXd& W, double sigma, bool upper) const;

  bool ok_ = false;
  Eigen::MatrixXd V_, U_, Vt_, Ut_;    // V, V⁻¹ and their transposes
  Eigen::MatrixXd T_, Z_;              // the (sorted) real Schur form
  std::vector<Block> blocks_;          // diagonal blocks of D
  double scale_ = 0.0, condition_ = 0.0;
  mutable Eigen::MatrixXd work_, rhs_;
  mutable Eigen::VectorXd vwork_;
};

}  // namespace freeflex
