// Lyapunov equations by the real Schur form (Bartels–Stewart): LyapunovSolver and the
// public solve_lyapunov.
#include "control/lyapunov_solvers.hpp"
#include "freeflex/control/lyapunov.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

namespace freeflex {

namespace {

using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 4, 4>;
using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 4, 1>;

template <int K>
bool fixed_solve(const Small& M, const SmallVec& b, SmallVec& v, double tiny) {
  const Eigen::Matrix<double, K, K> Mk = M;
  const Eigen::PartialPivLU<Eigen::Matrix<double, K, K>> lu(Mk);
  if (!(lu.matrixLU().diagonal().cwiseAbs().minCoeff() > tiny)) return false;
  v = lu.solve(Eigen::Matrix<double, K, 1>(b));
  return true;
}

/// Solves the 1, 2 or 4 dimensional system M v = b (fixed sizes: this is the inner loop
/// of every Lyapunov solve); false if M is singular to `tiny`.
bool small_solve(const Small& M, const SmallVec& b, SmallVec& v, double tiny) {
  switch (M.rows()) {
    case 1:
      if (!(std::abs(M(0, 0)) > tiny)) return false;
      v.resize(1);
      v(0) = b(0) / M(0, 0);
      return true;
    case 2:
      return fixed_solve<2>(M, b, v, tiny);
    case 4:
      return fixed_solve<4>(M, b, v, tiny);
    default: {
      const Eigen::FullPivLU<Small> lu(M);
      if (!(lu.matrixLU().diagonal().cwiseAbs().minCoeff() > tiny)) return false;
      v = lu.solve(b);
      return true;
    }
  }
}

}  // namespace

LyapunovSolver::LyapunovSolver(const Eigen::Ref<const Eigen::MatrixXd>& A) { factorize(A); }

void LyapunovSolver::factorize(const Eigen::Ref<const Eigen::MatrixXd>& A) {
  if (A.rows() != A.cols())
    throw std::invalid_argument("LyapunovSolver: expected a square A, got " + std::to_string(A.rows()) + " x " +
                                std::to_string(A.cols()));
  if (!A.allFinite()) throw std::invalid_argument("LyapunovSolver: A has a non-finite entry");
  Eigen::RealSchur<Eigen::MatrixXd> schur(A);
  T_ = schur.matrixT();
  Z_ = schur.matrixU();
  scale_ = A.norm();
  const int n = static_cast<int>(A.rows());
  start_.clear();
  size_.clear();
  for (int i = 0; i < n;) {
    const int sz = (i + 1 < n && T_(i + 1, i) != 0.0) ? 2 : 1;
    start_.push_back(i);
    size_.push_back(sz);
    i += sz;
  }
}

Eigen::VectorXcd LyapunovSolver::eigenvalues() const {
  Eigen::VectorXcd ev(T_.rows());
  for (std::size_t b = 0; b < start_.size(); ++b) {
    const int i = start_[b];
    if (size_[b] == 1) {
      ev(i) = T_(i, i);
    } else {
      const Eigen::Vector2cd e = Eigen::EigenSolver<Eigen::Matrix2d>(T_.block<2, 2>(i, i), false).eigenvalues();
      ev(i) = e(0);
      ev(i + 1) = e(1);
    }
  }
  return ev;
}

bool LyapunovSolver::solve(const Eigen::Ref<const Eigen::MatrixXd>& C, double sigma, Eigen::MatrixXd& X) const {
  const int n = size();
  if (C.rows() != n || C.cols() != n) return false;
  // Y = Zᵀ C Z, then (T + σ)ᵀ Y + Y (T + σ) = Y block by block:
  //   T_IIᵀ Y_IJ + Y_IJ T_JJ + 2σ Y_IJ = Ỹ_IJ − Σ_{K<I} T_KIᵀ Y_KJ − Σ_{L<J} Y_IL T_LJ
  work_.noalias() = Z_.transpose() * C * Z_;
  Eigen::MatrixXd& Y = work_;
  const double tiny = 64.0 * DBL_EPSILON * (scale_ + std::abs(sigma) + DBL_MIN);
  const int nb = static_cast<int>(start_.size());
  Small M;
  SmallVec b, v;
  for (int J = 0; J < nb; ++J) {
    const int j0 = start_[J], q = size_[J];
    if (j0 > 0) Y.middleCols(j0, q).noalias() -= Y.leftCols(j0) * T_.block(0, j0, j0, q);
    for (int I = 0; I < nb; ++I) {
      const int i0 = start_[I], p = size_[I];
      if (i0 > 0) Y.block(i0, j0, p, q).noalias() -= T_.block(0, i0, i0, p).transpose() * Y.block(0, j0, i0, q);
      // (I_q ⊗ T_IIᵀ + T_JJᵀ ⊗ I_p + 2σ I) vec(Y_IJ) = vec(rhs)
      M.setZero(p * q, p * q);
      for (int c = 0; c < q; ++c) M.block(c * p, c * p, p, p) = T_.block(i0, i0, p, p).transpose();
      for (int c = 0; c < q; ++c)
        for (int r = 0; r < q; ++r) M.block(c * p, r * p, p, p).diagonal().array() += T_(j0 + r, j0 + c);
      M.diagonal().array() += 2.0 * sigma;
      b.resize(p * q);
      for (int c = 0; c < q; ++c) b.segment(c * p, p) = Y.block(i0, j0 + c, p, 1);
      if (!small_solve(M, b, v, tiny)) return false;
      for (int c = 0; c < q; ++c) Y.block(i0, j0 + c, p, 1) = v.segment(c * p, p);
    }
  }
  X.noalias() = Z_ * Y * Z_.transpose();
  return X.allFinite();
}

bool LyapunovSolver::solve_transposed(const Eigen::Ref<const Eigen::VectorXd>& r, double mu,
                                      Eigen::VectorXd& z) const {
  const int n = size();
  if (r.size() != n) return false;
  // (Tᵀ + μ) y = Zᵀ r, block forward substitution
  Eigen::VectorXd y = Z_.transpose() * r;
  const double tiny = 64.0 * DBL_EPSILON * (scale_ + std::abs(mu) + DBL_MIN);
  Small M;
  SmallVec b, v;
  for (std::size_t I = 0; I < start_.size(); ++I) {
    const int i0 = start_[I], p = size_[I];
    b = y.segment(i0, p);
    if (i0 > 0) b.noalias() -= T_.block(0, i0, i0, p).transpose() * y.head(i0);
    M = T_.block(i0, i0, p, p).transpose();
    M.diagonal().array() += mu;
    if (!small_solve(M, b, v, tiny)) return false;
    y.segment(i0, p) = v;
  }
  z.noalias() = Z_ * y;
  return z.allFinite();
}

Eigen::MatrixXd solve_lyapunov(const Eigen::Ref<const Eigen::MatrixXd>& A, const Eigen::Ref<const Eigen::MatrixXd>& C) {
  if (C.rows() != A.rows() || C.cols() != A.cols())
    throw std::invalid_argument("solve_lyapunov: expected C of size " + std::to_string(A.rows()) + " x " +
                                std::to_string(A.cols()) + ", got " + std::to_string(C.rows()) + " x " +
                                std::to_string(C.cols()));
  const LyapunovSolver solver(A);
  Eigen::MatrixXd X;
  if (!solver.solve(-C, 0.0, X))
    throw std::runtime_error("solve_lyapunov: A and -A share an eigenvalue; the solution is not unique");
  return X;
}

}  // namespace freeflex
