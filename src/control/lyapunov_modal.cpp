// Lyapunov equations by a real block diagonalization of A (ModalLyapunovSolver): closed-
// form 2x2 blocks, four dense products per solve.
#include "control/lyapunov_solvers.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

namespace freeflex {

namespace {

// Adjacent 1x1 Schur blocks with |λ1 − λ2| < kMergeGap |t12| are kept as one 2x2 block
// (decoupling them would put an entry > 1/kMergeGap into Y).
constexpr double kMergeGap = 1e-3;

/// X (p x q, p, q in {1, 2}; in the top-left of the 2x2 matrices) with
///   c X + P X + X Qm = R,
/// P, Qm trace-free with P² = −dP I, Qm² = −dQ I (zero and 0 for a 1x1 side). The
/// operators P·, ·Qm commute, so the inverse is (c − P· − ·Qm)(s + 2 P·Qm)/(s² − 4 dP dQ)
/// with s = c² + dP + dQ. `sep` gets the smallest |c + λ(P) + λ(Qm)| (when dP, dQ >= 0)
/// or a comparable measure, for the singularity test. Used at factorization only.
Eigen::Matrix2d block_solve(int p, int q, double c, const Eigen::Matrix2d& P, double dP, const Eigen::Matrix2d& Qm,
                            double dQ, const Eigen::Matrix2d& R, double& sep) {
  Eigen::Matrix2d X = Eigen::Matrix2d::Zero();
  if (p == 1 && q == 1) {
    sep = std::abs(c);
    X(0, 0) = R(0, 0) / c;
  } else if (q == 1) {  // (c + P) x = r, (c + P)⁻¹ = (c − P)/(c² + dP)
    const double den = c * c + dP;
    sep = std::sqrt(std::abs(den));
    const Eigen::Vector2d r = R.col(0);
    X.col(0) = (c * r - P * r) / den;
  } else if (p == 1) {  // x (c + Qm) = r
    const double den = c * c + dQ;
    sep = std::sqrt(std::abs(den));
    const Eigen::RowVector2d r = R.row(0);
    X.row(0) = (c * r - r * Qm) / den;
  } else {
    const double s = c * c + dP + dQ;
    double den;
    if (dP >= 0.0 && dQ >= 0.0) {  // pairs ±iβ: s² − 4 dP dQ = (c² + (β_P − β_Q)²)(c² + (β_P + β_Q)²)
      const double bp = std::sqrt(dP), bq = std::sqrt(dQ);
      const double f1 = c * c + (bp - bq) * (bp - bq), f2 = c * c + (bp + bq) * (bp + bq);
      sep = std::sqrt(std::min(f1, f2));
      den = f1 * f2;
    } else {
      den = s * s - 4.0 * dP * dQ;
      sep = std::sqrt(std::sqrt(std::abs(den)));
    }
    const Eigen::Matrix2d Y = s * R + 2.0 * (P * R * Qm);
    X = (c * Y - P * Y - Y * Qm) / den;
  }
  return X;
}

/// Swaps the adjacent diagonal blocks of sizes p and q starting at row j of the real
/// Schur form T (and the columns of Z), by an orthogonal similarity (LAPACK's direct
/// swap, dlaexc). False, changing nothing, when the swap would not keep T block upper
/// triangular to round-off (blocks with close eigenvalues).
bool swap_blocks(Eigen::MatrixXd& T, Eigen::MatrixXd& Z, int j, int p, int q) {
  const int n = static_cast<int>(T.rows()), m = p + q;
  Eigen::MatrixXd Qs;
  if (p == 1 && q == 1) {  // a Givens rotation taking [t12; t22 − t11] to [r; 0]
    const double f = T(j, j + 1), g = T(j + 1, j + 1) - T(j, j), r = std::hypot(f, g);
    if (r == 0.0) return true;  // equal eigenvalues, no coupling: nothing to swap
    Qs.resize(2, 2);
    Qs << f / r, -g / r, g / r, f / r;
  } else {  // T11 X − X T22 = T12, then Q from the QR of [−X; I]
    const Eigen::MatrixXd T11 = T.block(j, j, p, p), T22 = T.block(j + p, j + p, q, q), T12 = T.block(j, j + p, p, q);
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(p * q, p * q);
    for (int c = 0; c < q; ++c)
      for (int r = 0; r < p; ++r)
        for (int k = 0; k < p; ++k) K(r + p * c, k + p * c) += T11(r, k);
    for (int c = 0; c < q; ++c)
      for (int r = 0; r < p; ++r)
        for (int k = 0; k < q; ++k) K(r + p * c, r + p * k) -= T22(k, c);
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(K);
    if (!lu.isInvertible()) return false;
    const Eigen::VectorXd x = lu.solve(Eigen::Map<const Eigen::VectorXd>(T12.data(), p * q));
    Eigen::MatrixXd M(m, q);
    M.topRows(p) = -Eigen::Map<const Eigen::MatrixXd>(x.data(), p, q);
    M.bottomRows(q).setIdentity();
    Qs = Eigen::HouseholderQR<Eigen::MatrixXd>(M).householderQ();
  }
  const Eigen::MatrixXd D = Qs.transpose() * T.block(j, j, m, m) * Qs;
  // the new (2,1) block must vanish: else the blocks were too close to swap stably
  if (!(D.bottomLeftCorner(p, q).norm() <= 1e-12 * (T.block(j, j, m, m).norm() + DBL_MIN))) return false;
  T.middleRows(j, m) = Qs.transpose() * T.middleRows(j, m);
  T.middleCols(j, m) = T.middleCols(j, m) * Qs;
  Z.middleCols(j, m) = Z.middleCols(j, m) * Qs;
  T.block(j + q, j, p, q).setZero();
  for (int i = j + m; i < n; ++i) T.block(i, j, 1, m).setZero();  // round-off below the blocks
  return true;
}

/// Moves the real eigenvalues of T to its end, sorted, so that near-equal ones become
/// adjacent (a near-defective pair is merged only when adjacent); swaps that would not be
/// stable are skipped. Costs O(n) swaps of O(n) each.
void sort_real_eigenvalues(Eigen::MatrixXd& T, Eigen::MatrixXd& Z) {
  const int n = static_cast<int>(T.rows());
  auto size_at = [&](int i) { return (i + 1 < n && T(i + 1, i) != 0.0) ? 2 : 1; };
  for (bool moved = true; moved;) {
    moved = false;
    for (int i = 0; i < n;) {
      const int p = size_at(i);
      if (i + p >= n) break;
      const int q = size_at(i + p);
      // a real block before a complex one, or two reals out of order
      const bool out_of_order = p == 1 && (q == 2 || T(i, i) > T(i + 1, i + 1));
      if (out_of_order && swap_blocks(T, Z, i, p, q)) {
        moved = true;
        i += q;
      } else {
        i += p;
      }
    }
  }
}

}  // namespace

bool ModalLyapunovSolver::factorize(const Eigen::Ref<const Eigen::MatrixXd>& A, double max_condition, bool sort) {
  if (A.rows() != A.cols())
    throw std::invalid_argument("ModalLyapunovSolver: expected a square A, got " + std::to_string(A.rows()) + " x " +
                                std::to_string(A.cols()));
  if (!A.allFinite()) throw std::invalid_argument("ModalLyapunovSolver: A has a non-finite entry");
  ok_ = false;
  condition_ = std::numeric_limits<double>::infinity();
  const int n = static_cast<int>(A.rows());
  const Eigen::RealSchur<Eigen::MatrixXd> schur(A);
  if (schur.info() != Eigen::Success) return false;
  T_ = schur.matrixT();
  Z_ = schur.matrixU();
  if (sort) sort_real_eigenvalues(T_, Z_);
  const Eigen::MatrixXd& T = T_;
  scale_ = A.norm();
  blocks_.clear();
  std::vector<Eigen::Matrix2d> N;
  for (int i = 0; i < n;) {
    int sz = (i + 1 < n && T(i + 1, i) != 0.0) ? 2 : 1;
    // Two adjacent real eigenvalues much closer than their coupling (a near-defective
    // pair the Schur form split, e.g. ±3e-7 with coupling 1 for a double integrator)
    // stay together as one 2x2 block.
    if (sz == 1 && i + 1 < n && (i + 2 >= n || T(i + 2, i + 1) == 0.0) &&
        std::abs(T(i, i) - T(i + 1, i + 1)) < kMergeGap * std::abs(T(i, i + 1)))
      sz = 2;
    Block b{i, sz, T(i, i), 0.0, 0.0, 0.0, 0.0, -1.0};
    Eigen::Matrix2d Nb = Eigen::Matrix2d::Zero();
    if (sz == 2) {
      b.mid = 0.5 * (T(i, i) + T(i + 1, i + 1));
      b.n00 = 0.5 * (T(i, i) - T(i + 1, i + 1));
      b.n01 = T(i, i + 1);
      b.n10 = T(i + 1, i);
      Nb << b.n00, b.n01, b.n10, -b.n00;
      b.det = -b.n00 * b.n00 - b.n01 * b.n10;
      if (b.det > 0.0) b.beta = std::sqrt(b.det);
    }
    blocks_.push_back(b);
    N.push_back(Nb);
    i += sz;
  }
  // T Y = Y D, Y unit upper triangular: for I < J (from the diagonal up)
  //   T_II Y_IJ − Y_IJ T_JJ = −Σ_{I<K≤J} T_IK Y_KJ
  const int nb = static_cast<int>(blocks_.size());
  Eigen::MatrixXd Y = Eigen::MatrixXd::Identity(n, n);
  const double tiny = 64.0 * DBL_EPSILON * (scale_ + DBL_MIN);
  for (int J = 1; J < nb; ++J) {
    const int j0 = blocks_[J].start, q = blocks_[J].size;
    for (int I = J - 1; I >= 0; --I) {
      const int i0 = blocks_[I].start, p = blocks_[I].size, k0 = i0 + p, len = j0 + q - k0;
      Eigen::Matrix2d R = Eigen::Matrix2d::Zero();
      R.topLeftCorner(p, q).noalias() = -T.block(i0, k0, p, len) * Y.block(k0, j0, len, q);
      double sep = 0.0;
      const Eigen::Matrix2d X =
          block_solve(p, q, blocks_[I].mid - blocks_[J].mid, N[I], blocks_[I].det, -N[J], blocks_[J].det, R, sep);
      if (!(sep > tiny)) return false;  // blocks I and J share an eigenvalue
      Y.block(i0, j0, p, q) = X.topLeftCorner(p, q);
    }
  }
  V_.noalias() = Z_ * Y;
  const Eigen::MatrixXd Yinv = Y.triangularView<Eigen::UnitUpper>().solve(Eigen::MatrixXd::Identity(n, n));
  U_.noalias() = Yinv * Z_.transpose();
  // balance: one scale per block commutes with D
  for (const Block& b : blocks_) {
    const double nrm = V_.middleCols(b.start, b.size).norm() / std::sqrt(double(b.size));
    if (!(nrm > 0.0) || !std::isfinite(nrm)) return false;
    V_.middleCols(b.start, b.size) /= nrm;
    U_.middleRows(b.start, b.size) *= nrm;
  }
  if (!V_.allFinite() || !U_.allFinite()) return false;
  Vt_ = V_.transpose();
  Ut_ = U_.transpose();
  condition_ = V_.cwiseAbs().colwise().sum().maxCoeff() * U_.cwiseAbs().colwise().sum().maxCoeff();
  if (!(condition_ <= max_condition)) return false;
  work_.resize(n, n);
  rhs_.resize(n, n);
  vwork_.resize(n);
  ok_ = true;
  return true;
}

Eigen::VectorXcd ModalLyapunovSolver::eigenvalues() const {
  Eigen::VectorXcd ev(size());
  for (const Block& b : blocks_) {
    if (b.size == 1) {
      ev(b.start) = b.mid;
    } else {  // mid ± sqrt(−det N)
      const std::complex<double> r = std::sqrt(std::complex<double>(-b.det, 0.0));
      ev(b.start) = b.mid + r;
      ev(b.start + 1) = b.mid - r;
    }
  }
  return ev;
}

bool ModalLyapunovSolver::solve_blocks(Eigen::MatrixXd& W, double sigma, bool upper) const {
  // Block (I, J): c W + N_Iᵀ W + W N_J = R with c = mid_I + mid_J + 2σ (block_solve with
  // P = N_Iᵀ, Qm = N_J), written out: this loop runs n²/4 times per Newton iteration.
  const int n = size();
  const double tiny = 64.0 * DBL_EPSILON * (scale_ + std::abs(sigma) + DBL_MIN), tiny2 = tiny * tiny;
  double* w = W.data();
  const int nb = static_cast<int>(blocks_.size());
  for (int J = 0; J < nb; ++J) {
    const Block& bj = blocks_[J];
    double* c0 = w + static_cast<std::ptrdiff_t>(bj.start) * n;  // column j
    double* c1 = c0 + n;                                            // column j + 1 (2x2 J)
    const double cj = bj.mid + 2.0 * sigma;
    for (int I = 0; I < (upper ? J + 1 : nb); ++I) {
      const Block& bi = blocks_[I];
      const int i = bi.start;
      const double c = bi.mid + cj;
      if (bi.size == 1 && bj.size == 1) {
        if (!(std::abs(c) > tiny)) return false;
        c0[i] /= c;
      } else if (bj.size == 1) {  // (c + N_Iᵀ) x = r:  x = (c − N_Iᵀ) r / (c² + det)
        const double den = c * c + bi.det;
        if (!(std::abs(den) > tiny2)) return false;
        const double r0 = c0[i], r1 = c0[i + 1];
        c0[i] = (c * r0 - (bi.n00 * r0 + bi.n10 * r1)) / den;
        c0[i + 1] = (c * r1 - (bi.n01 * r0 - bi.n00 * r1)) / den;
      } else if (bi.size == 1) {  // x (c + N_J) = r:  x = r (c − N_J) / (c² + det)
        const double den = c * c + bj.det;
        if (!(std::abs(den) > tiny2)) return false;
        const double r0 = c0[i], r1 = c1[i];
        c0[i] = (c * r0 - (r0 * bj.n00 + r1 * bj.n10)) / den;
        c1[i] = (c * r1 - (r0 * bj.n01 - r1 * bj.n00)) / den;
      } else {
        const double s = c * c + bi.det + bj.det;
        double den;
        if (bi.beta >= 0.0 && bj.beta >= 0.0) {
          const double dm = bi.beta - bj.beta, dp = bi.beta + bj.beta;
          const double f1 = c * c + dm * dm, f2 = c * c + dp * dp;
          if (!(std::min(f1, f2) > tiny2)) return false;
          den = f1 * f2;
        } else {
          den = s * s - 4.0 * bi.det * bj.det;
          if (!(std::abs(den) > tiny2 * tiny2)) return false;
        }
        // P = N_Iᵀ = [[a, v], [u, −a]] (a = n00, u = n01, v = n10), Q = N_J = [[e, f], [g, −e]]
        const double a = bi.n00, u = bi.n01, v = bi.n10;
        const double e = bj.n00, f = bj.n01, g = bj.n10;
        // (a diagonal block of the upper triangle only: its lower entry is the mirror)
        const double r00 = c0[i], r10 = (upper && I == J) ? c1[i] : c0[i + 1], r01 = c1[i], r11 = c1[i + 1];
        // PR
        const double pr00 = a * r00 + v * r10, pr01 = a * r01 + v * r11;
        const double pr10 = u * r00 - a * r10, pr11 = u * r01 - a * r11;
        // Y = s R + 2 (P R) Q
        const double y00 = s * r00 + 2.0 * (pr00 * e + pr01 * g), y01 = s * r01 + 2.0 * (pr00 * f - pr01 * e);
        const double y10 = s * r10 + 2.0 * (pr10 * e + pr11 * g), y11 = s * r11 + 2.0 * (pr10 * f - pr11 * e);
        // X = (c Y − P Y − Y Q) / den
        const double inv = 1.0 / den;
        c0[i] = (c * y00 - (a * y00 + v * y10) - (y00 * e + y01 * g)) * inv;
        c1[i] = (c * y01 - (a * y01 + v * y11) - (y00 * f - y01 * e)) * inv;
        c0[i + 1] = (c * y10 - (u * y00 - a * y10) - (y10 * e + y11 * g)) * inv;
        c1[i + 1] = (c * y11 - (u * y01 - a * y11) - (y10 * f - y11 * e)) * inv;
      }
    }
  }
  return true;
}

bool ModalLyapunovSolver::solve(const Eigen::Ref<const Eigen::MatrixXd>& C, double sigma, Eigen::MatrixXd& X) const {
  const int n = size();
  if (!ok_ || C.rows() != n || C.cols() != n) return false;
  work_.noalias() = C * V_;
  rhs_.noalias() = V_.transpose() * work_;  // Vᵀ C V, overwritten by W
  if (!solve_blocks(rhs_, sigma, false)) return false;
  work_.noalias() = rhs_ * U_;
  X.resize(n, n);
  X.noalias() = U_.transpose() * work_;
  return X.allFinite();
}

bool ModalLyapunovSolver::solve_symmetric(const Eigen::Ref<const Eigen::MatrixXd>& C, double sigma,
                                          Eigen::MatrixXd& X) const {
  const int n = size();
  if (!ok_ || C.rows() != n || C.cols() != n) return false;
  // C V, then Vᵀ (C V) (upper triangle): W's right-hand side
  if (C.outerStride() == n) {
    detail::small_gemm(n, C.data(), V_.data(), work_.data(), false);
  } else {
    rhs_ = C;
    detail::small_gemm(n, rhs_.data(), V_.data(), work_.data(), false);
  }
  detail::small_gemm(n, Vt_.data(), work_.data(), rhs_.data(), true);
  if (!solve_blocks(rhs_, sigma, true)) return false;
  rhs_.triangularView<Eigen::StrictlyLower>() = rhs_.transpose();
  // X = V⁻ᵀ W V⁻¹ (upper triangle, then mirrored)
  detail::small_gemm(n, rhs_.data(), U_.data(), work_.data(), false);
  X.resize(n, n);
  detail::small_gemm(n, Ut_.data(), work_.data(), X.data(), true);
  X.triangularView<Eigen::StrictlyLower>() = X.transpose();
  return X.allFinite();
}

bool ModalLyapunovSolver::solve_transposed(const Eigen::Ref<const Eigen::VectorXd>& r, double mu,
                                           Eigen::VectorXd& z) const {
  const int n = size();
  if (!ok_ || r.size() != n) return false;
  // (Dᵀ + μ) u = Vᵀ r, z = V⁻ᵀ u;  block: (c + N_Iᵀ) u = y, u = (c − N_Iᵀ) y / (c² + det)
  vwork_.noalias() = V_.transpose() * r;
  const double tiny = 64.0 * DBL_EPSILON * (scale_ + std::abs(mu) + DBL_MIN);
  for (const Block& b : blocks_) {
    const int i = b.start;
    const double c = b.mid + mu;
    if (b.size == 1) {
      if (!(std::abs(c) > tiny)) return false;
      vwork_(i) /= c;
    } else {
      const double den = c * c + b.det;
      if (!(std::abs(den) > tiny * tiny)) return false;
      const double y0 = vwork_(i), y1 = vwork_(i + 1);
      vwork_(i) = (c * y0 - (b.n00 * y0 + b.n10 * y1)) / den;
      vwork_(i + 1) = (c * y1 - (b.n01 * y0 - b.n00 * y1)) / den;
    }
  }
  z.resize(n);
  z.noalias() = U_.transpose() * vwork_;
  return z.allFinite();
}


}  // namespace freeflex
