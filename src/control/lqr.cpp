// Steady-state LQR: the CARE by the stable invariant subspace with Newton–Kleinman polish,
// uncontrollable modes split off; weight checks and the vibration weight.
#include "freeflex/control/lqr.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <optional>
#include <utility>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "control/lyapunov_solvers.hpp"
#include "freeflex/control/lyapunov.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string fmt(double v) { return util::format_number(v, 6); }

std::string fmt(std::complex<double> v) {
  std::ostringstream os;
  os.precision(4);
  os << v.real() << (v.imag() < 0 ? " - " : " + ") << std::abs(v.imag()) << "i";
  return os.str();
}

std::string size_str(Eigen::Index r, Eigen::Index c) { return std::to_string(r) + " x " + std::to_string(c); }

void check_square(const Eigen::Ref<const Eigen::MatrixXd>& W, int n, const std::string& name,
                  const std::string& where) {
  if (W.rows() != n || W.cols() != n)
    throw std::invalid_argument(where + ": " + name + " must be " + size_str(n, n) + ", got " +
                                size_str(W.rows(), W.cols()));
  if (!W.allFinite()) throw std::invalid_argument(where + ": " + name + " has a non-finite entry");
  const double scale = W.cwiseAbs().maxCoeff();
  const double asym = (W - W.transpose()).cwiseAbs().maxCoeff();
  if (asym > 1e-10 * scale)
    throw std::invalid_argument(where + ": " + name + " must be symmetric: max |" + name + " - " + name +
                                "ᵀ| = " + fmt(asym) + ", largest entry " + fmt(scale));
}

/// Diagonal similarity D (powers of two) making row and column norms of D⁻¹ A D comparable
/// (LAPACK's gebal without permutations): the staircase's rank decisions then do not
/// depend on the units of the coordinates.
Eigen::VectorXd balance(const Eigen::MatrixXd& A0) {
  Eigen::MatrixXd A = A0;
  const int n = static_cast<int>(A.rows());
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  for (int sweep = 0; sweep < 50; ++sweep) {
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      // off-diagonal column and row norms
      const double aii2 = A(i, i) * A(i, i);
      const double cc = std::sqrt(std::max(0.0, A.col(i).squaredNorm() - aii2));
      const double rr = std::sqrt(std::max(0.0, A.row(i).squaredNorm() - aii2));
      if (cc == 0.0 || rr == 0.0) continue;
      const double f = std::exp2(std::round(0.5 * std::log2(rr / cc)));
      if (f == 1.0) continue;
      if (cc * cc * f * f + rr * rr / (f * f) >= 0.95 * (cc * cc + rr * rr)) continue;
      A.col(i) *= f;
      A.row(i) /= f;
      d(i) *= f;
      changed = true;
    }
    if (!changed) break;
  }
  return d;
}

/// Orthonormal basis of the controllable subspace of (A, B): block Krylov with full
/// re-orthogonalization and SVD rank decisions, singular values above `tol_b` for the
/// first block (B) and `tol_a` for the later ones (A times an orthonormal block).
Eigen::MatrixXd krylov_controllable(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double tol_b, double tol_a) {
  const int n = static_cast<int>(A.rows());
  Eigen::MatrixXd V(n, 0);
  Eigen::MatrixXd W = B;
  double abs_tol = tol_b;
  while (V.cols() < n && W.cols() > 0) {
    for (int pass = 0; pass < 2; ++pass)
      if (V.cols() > 0) W -= V * (V.transpose() * W);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(W, Eigen::ComputeThinU);
    int r = 0;
    while (r < svd.singularValues().size() && svd.singularValues()(r) > abs_tol) ++r;
    r = std::min<int>(r, n - static_cast<int>(V.cols()));
    if (r == 0) break;
    const Eigen::MatrixXd Vn = svd.matrixU().leftCols(r);
    Eigen::MatrixXd Vnew(n, V.cols() + r);
    Vnew << V, Vn;
    V = Vnew;
    W = A * Vn;
    abs_tol = tol_a;
  }
  return V;
}

/// Swaps the adjacent diagonal entries k, k+1 of the upper triangular T (A = U T U^H).
void swap_schur(Eigen::MatrixXcd& T, Eigen::MatrixXcd& U, int k) {
  const std::complex<double> t11 = T(k, k), t22 = T(k + 1, k + 1), t12 = T(k, k + 1);
  // eigenvector of the 2x2 block for t22 becomes the first basis vector
  Eigen::Vector2cd v(t12, t22 - t11);
  const double nrm = v.norm();
  if (nrm == 0.0) return;
  v /= nrm;
  Eigen::Matrix2cd Z;
  Z << v(0), -std::conj(v(1)), v(1), std::conj(v(0));
  T.middleRows(k, 2) = (Z.adjoint() * T.middleRows(k, 2)).eval();
  T.middleCols(k, 2) = (T.middleCols(k, 2) * Z).eval();
  U.middleCols(k, 2) = (U.middleCols(k, 2) * Z).eval();
  T(k + 1, k) = 0.0;
}

/// Orthonormal basis (original coordinates) of the left-uncontrollable subspace of
/// (A, B) restricted to the modes that are not asymptotically stable (Re λ >= −δ).
/// A block-Krylov staircase on the whole system loses low-frequency directions under the
/// powers of A when frequencies spread over decades (NOA 20: ‖A‖ ~ 7e9). Instead, each
/// cluster of non-stable eigenvalues (the rigid-body modes at 0, each undamped elastic
/// pair) is split off by reordering the complex Schur form of the balanced Aᵀ, and the
/// staircase runs on that small block, where the dual PBH test is well conditioned.
Eigen::MatrixXd unstable_uncontrollable(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double tol) {
  const int n = static_cast<int>(A.rows());
  const Eigen::VectorXd d = balance(A);
  const Eigen::MatrixXd Ab = d.cwiseInverse().asDiagonal() * A * d.asDiagonal();
  const Eigen::MatrixXd Bb = d.cwiseInverse().asDiagonal() * B;
  const double nA = std::max(Ab.norm(), 1.0), nB = std::max(Bb.norm(), DBL_MIN);
  Eigen::ComplexSchur<Eigen::MatrixXcd> schur(Ab.transpose().cast<std::complex<double>>());
  const Eigen::MatrixXcd T0 = schur.matrixT(), U0 = schur.matrixU();
  const Eigen::VectorXcd lam = T0.diagonal();
  // δ well above the round-off spread of the defective rigid-body eigenvalues (~1e-4 at NOA 20)
  const double delta = 1e-6 * nA;
  // clusters of non-stable eigenvalues by single linkage
  std::vector<int> cluster(n, -1);
  int nc = 0;
  for (int i = 0; i < n; ++i) {
    if (lam(i).real() < -delta || cluster[i] >= 0) continue;
    cluster[i] = nc;
    for (bool grown = true; grown;) {
      grown = false;
      for (int j = 0; j < n; ++j) {
        if (cluster[j] >= 0 || lam(j).real() < -delta) continue;
        for (int k = 0; k < n; ++k)
          if (cluster[k] == nc && std::abs(lam(j) - lam(k)) <= 2.0 * delta + 1e-8 * std::abs(lam(k))) {
            cluster[j] = nc;
            grown = true;
            break;
          }
      }
    }
    ++nc;
  }
  std::vector<Eigen::VectorXcd> done_means;
  Eigen::MatrixXd Wb(n, 0);
  for (int c = 0; c < nc; ++c) {
    std::complex<double> mean = 0.0;
    int size = 0;
    for (int i = 0; i < n; ++i)
      if (cluster[i] == c) mean += lam(i), ++size;
    mean /= double(size);
    bool mirror = false;  // the conjugate cluster of one already done: same real subspace
    for (const auto& mvec : done_means)
      if (std::abs(std::conj(mean) - mvec(0)) <= 2.0 * delta + 1e-8 * std::abs(mean)) mirror = true;
    if (mirror) continue;
    done_means.push_back(Eigen::VectorXcd::Constant(1, mean));
    Eigen::MatrixXcd T = T0, U = U0;
    std::vector<char> sel(n);
    for (int i = 0; i < n; ++i) sel[i] = cluster[i] == c;
    int k = 0;
    for (int i = 0; i < n; ++i)
      if (sel[i]) {
        for (int j = i - 1; j >= k; --j) {
          swap_schur(T, U, j);
          std::swap(sel[j], sel[j + 1]);
        }
        ++k;
      }
    Eigen::MatrixXd ReIm(n, 2 * k);
    ReIm << U.leftCols(k).real(), U.leftCols(k).imag();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(ReIm, Eigen::ComputeThinU);
    int rr = 0;
    while (rr < svd.singularValues().size() && svd.singularValues()(rr) > 1e-8 * svd.singularValues()(0)) ++rr;
    const Eigen::MatrixXd Zr = svd.matrixU().leftCols(rr);
    const Eigen::MatrixXd Tr = Zr.transpose() * Ab.transpose() * Zr;  // Abᵀ on the cluster
    const Eigen::MatrixXd Cr = Bb.transpose() * Zr;
    // observable subspace of (Cr, Tr) = controllable subspace of (Trᵀ, Crᵀ); its complement
    // is the largest Tr-invariant subspace in ker Cr: the uncontrollable modes
    const double shift = mean.real();  // the cluster's own eigenvalue adds no direction
    const Eigen::MatrixXd Ts = Tr.transpose() - shift * Eigen::MatrixXd::Identity(rr, rr);
    const Eigen::MatrixXd Vo = krylov_controllable(Ts, Cr.transpose(), tol * nB, tol * nA);
    const int r = static_cast<int>(Vo.cols());
    if (r == rr) continue;
    Eigen::MatrixXd Nu;
    if (r == 0) {
      Nu = Eigen::MatrixXd::Identity(rr, rr);
    } else {
      Eigen::HouseholderQR<Eigen::MatrixXd> qr(Vo);
      Nu = (qr.householderQ() * Eigen::MatrixXd::Identity(rr, rr)).rightCols(rr - r);
    }
    Eigen::MatrixXd grown(n, Wb.cols() + Nu.cols());
    grown << Wb, Zr * Nu;
    Wb = grown;
  }
  if (Wb.cols() == 0) return Eigen::MatrixXd(n, 0);
  // left vectors transform as w = D⁻¹ w_b
  const Eigen::MatrixXd W = d.cwiseInverse().asDiagonal() * Wb;
  Eigen::HouseholderQR<Eigen::MatrixXd> qw(W);
  return qw.householderQ() * Eigen::MatrixXd::Identity(n, W.cols());
}

Eigen::MatrixXd riccati_residual(const Eigen::MatrixXd& A, const Eigen::MatrixXd& S, const Eigen::MatrixXd& Q,
                                 const Eigen::MatrixXd& P) {
  Eigen::MatrixXd AtP = A.transpose() * P;
  Eigen::MatrixXd Res = AtP + AtP.transpose() - P * S * P + Q;
  return 0.5 * (Res + Res.transpose());
}

}  // namespace

namespace {
/// The smallest eigenvalue of W's symmetric part and the largest magnitude, after the
/// size check; none for an empty W.
std::optional<std::pair<double, double>> eigenvalue_range(const Eigen::Ref<const Eigen::MatrixXd>& W, int n,
                                                          const std::string& name, const std::string& where) {
  check_square(W, n, name, where);
  if (n == 0) return std::nullopt;
  const Eigen::MatrixXd Ws = 0.5 * (W + W.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Ws, Eigen::EigenvaluesOnly);
  return std::make_pair(es.eigenvalues()(0), es.eigenvalues().cwiseAbs().maxCoeff());
}
}  // namespace

void check_positive_semidefinite(const Eigen::Ref<const Eigen::MatrixXd>& W, int n, const std::string& name,
                                 const std::string& where) {
  const auto range = eigenvalue_range(W, n, name, where);
  if (range && range->first < -1e-10 * range->second)
    throw std::invalid_argument(where + ": " + name + " must be positive semidefinite: smallest eigenvalue " +
                                fmt(range->first));
}

void check_positive_definite(const Eigen::Ref<const Eigen::MatrixXd>& W, int n, const std::string& name,
                             const std::string& where) {
  const auto range = eigenvalue_range(W, n, name, where);
  if (range && (!(range->first > 1e-14 * range->second) || !(range->first > 0.0)))
    throw std::invalid_argument(where + ": " + name + " must be positive definite: smallest eigenvalue " +
                                fmt(range->first));
}

namespace {
bool care_options_valid(const CareOptions& opt) {
  return opt.controllability_tolerance > 0.0 && opt.imaginary_axis_tolerance > 0.0 && opt.max_newton_iterations >= 0;
}
}  // namespace

void validate(const CareOptions& opt) {
  if (!care_options_valid(opt))
    throw std::invalid_argument("CARE options: tolerances must be > 0 and max_newton_iterations >= 0");
}

CareResult solve_care(const Eigen::Ref<const Eigen::MatrixXd>& A_in, const Eigen::Ref<const Eigen::MatrixXd>& B_in,
                      const Eigen::Ref<const Eigen::MatrixXd>& Q_in, const Eigen::Ref<const Eigen::MatrixXd>& R_in,
                      const CareOptions& opt) {
  const std::string where = "solve_care";
  const int n = static_cast<int>(A_in.rows());
  if (n < 1 || A_in.cols() != n)
    throw std::invalid_argument(where + ": A must be square and non-empty, got " + size_str(A_in.rows(), A_in.cols()));
  if (!A_in.allFinite()) throw std::invalid_argument(where + ": A has a non-finite entry");
  const int m = static_cast<int>(B_in.cols());
  if (B_in.rows() != n || m < 1)
    throw std::invalid_argument(where + ": B must be " + std::to_string(n) + " x m with m >= 1, got " +
                                size_str(B_in.rows(), B_in.cols()));
  if (!B_in.allFinite()) throw std::invalid_argument(where + ": B has a non-finite entry");
  check_positive_semidefinite(Q_in, n, "Q", where);
  check_positive_definite(R_in, m, "R", where);
  if (!care_options_valid(opt))
    throw std::invalid_argument(where + ": tolerances must be > 0 and max_newton_iterations >= 0");

  const Eigen::MatrixXd A = A_in, B = B_in;
  const Eigen::MatrixXd Q = 0.5 * (Q_in + Q_in.transpose());
  const Eigen::MatrixXd R = 0.5 * (R_in + R_in.transpose());
  const Eigen::LLT<Eigen::MatrixXd> Rllt(R);
  const Eigen::MatrixXd W = Rllt.matrixL().solve(B.transpose());  // L⁻¹ Bᵀ
  const Eigen::MatrixXd S_full = W.transpose() * W;               // B R⁻¹ Bᵀ

  CareResult res;
  // 1. Uncontrollable modes that are not asymptotically stable.
  const Eigen::MatrixXd Wu = unstable_uncontrollable(A, B, opt.controllability_tolerance);
  const int d = static_cast<int>(Wu.cols());
  res.uncontrollable_dimension = d;
  bool reduce = false;
  Eigen::MatrixXd Vc;
  if (d > 0) {
    res.uncontrollable_eigenvalues = Eigen::EigenSolver<Eigen::MatrixXd>(Wu.transpose() * A * Wu, false).eigenvalues();
    std::string list;
    for (int i = 0; i < d && list.size() < 200; ++i)
      list += (list.empty() ? "" : ", ") + fmt(res.uncontrollable_eigenvalues(i));
    if (!opt.restrict_to_controllable) {
      res.status = CareResult::Status::NotStabilizable;
      res.message = "(A, B) is not stabilizable: " + std::to_string(d) +
                    " uncontrollable mode(s), not asymptotically stable: " + list +
                    " (set restrict_to_controllable to regulate the rest only)";
      return res;
    }
    // V: orthonormal complement of Wu, an A-invariant subspace holding range(B)
    Eigen::HouseholderQR<Eigen::MatrixXd> qr(Wu);
    Vc = (qr.householderQ() * Eigen::MatrixXd::Identity(n, n)).rightCols(n - d);
    reduce = true;
    res.message = "solved on the complement of " + std::to_string(d) +
                  " uncontrollable, not asymptotically stable mode(s) (dimension " + std::to_string(n - d) + " of " +
                  std::to_string(n) + "); they keep zero gain: " + list;
  }
  const Eigen::MatrixXd V = reduce ? Vc : Eigen::MatrixXd::Identity(n, n);
  const int nr = static_cast<int>(V.cols());
  const Eigen::MatrixXd Ar = V.transpose() * A * V;
  const Eigen::MatrixXd Sr = V.transpose() * S_full * V;
  const Eigen::MatrixXd Qr = V.transpose() * Q * V;

  // 2. Stable invariant subspace of the Hamiltonian.
  Eigen::MatrixXd H(2 * nr, 2 * nr);
  H << Ar, -Sr, -Qr, -Ar.transpose();
  Eigen::ComplexSchur<Eigen::MatrixXcd> schur(H.cast<std::complex<double>>());
  if (schur.info() != Eigen::Success) {
    res.status = CareResult::Status::Failed;
    res.message = "the Schur decomposition of the Hamiltonian did not converge";
    return res;
  }
  Eigen::MatrixXcd T = schur.matrixT(), U = schur.matrixU();
  // Relative to |λ| (a lightly damped 4000 rad/s mode has |Re λ| / |λ| ~ 1e-3, not 0)
  // plus a round-off floor relative to ‖H‖.
  const double floor_tol = 1e3 * DBL_EPSILON * H.norm();
  int stable = 0;
  for (int i = 0; i < 2 * nr; ++i) {
    const double re = T(i, i).real();
    if (std::abs(re) <= opt.imaginary_axis_tolerance * std::abs(T(i, i)) + floor_tol) {
      res.status = CareResult::Status::NoStabilizingSolution;
      res.message = "the Hamiltonian has an eigenvalue on the imaginary axis (" + fmt(T(i, i)) +
                    "): (A, B) not stabilizable or (Q, A) not detectable there";
      return res;
    }
    if (re < 0.0) ++stable;
  }
  if (stable != nr) {
    res.status = CareResult::Status::Failed;
    res.message = "the Hamiltonian has " + std::to_string(stable) + " stable eigenvalues, expected " +
                  std::to_string(nr);
    return res;
  }
  for (int i = 0, k = 0; i < 2 * nr; ++i) {
    if (T(i, i).real() < 0.0) {
      for (int j = i - 1; j >= k; --j) swap_schur(T, U, j);
      ++k;
    }
  }
  const Eigen::MatrixXcd X = U.topLeftCorner(nr, nr), Y = U.bottomLeftCorner(nr, nr);
  Eigen::PartialPivLU<Eigen::MatrixXcd> lu(X.transpose());
  const Eigen::MatrixXcd Pc = lu.solve(Y.transpose()).transpose();
  Eigen::MatrixXd P = Pc.real();
  P = 0.5 * (P + P.transpose()).eval();
  if (!P.allFinite()) {
    res.status = CareResult::Status::Failed;
    res.message = "the stable invariant subspace has a singular upper block";
    return res;
  }

  // 3. Newton–Kleinman polish.
  const double qn = Qr.norm();
  auto rel = [&](const Eigen::MatrixXd& Pm) {
    const double den = qn > 0.0 ? qn : std::max((Pm * Sr * Pm).norm(), DBL_MIN);
    return riccati_residual(Ar, Sr, Qr, Pm).norm() / den;
  };
  double best = rel(P);
  res.residual_before_newton = best;
  for (int it = 0; it < opt.max_newton_iterations; ++it) {
    const Eigen::MatrixXd Ak = Ar - Sr * P;
    LyapunovSolver lyap(Ak);
    Eigen::MatrixXd dP;
    if (!lyap.solve(riccati_residual(Ar, Sr, Qr, P), 0.0, dP)) break;  // Akᵀ dP + dP Ak = −Res
    Eigen::MatrixXd Pn = P - dP;  // solve() gives (Ak)ᵀ X + X Ak = Res, so ΔP = −X
    Pn = 0.5 * (Pn + Pn.transpose()).eval();
    const double rn = rel(Pn);
    if (!(rn < best)) break;
    const bool enough = !(rn < 0.5 * best);
    P = Pn;
    best = rn;
    res.newton_iterations = it + 1;
    if (enough) break;
  }
  res.residual = best;
  {
    const Eigen::MatrixXd AtP = Ar.transpose() * P;
    const double den = Qr.norm() + 2.0 * AtP.norm() + (P * Sr * P).norm();
    res.residual_normwise = riccati_residual(Ar, Sr, Qr, P).norm() / std::max(den, DBL_MIN);
  }

  // 4. Gain and closed loop.
  const Eigen::MatrixXd Acl_r = Ar - Sr * P;
  const Eigen::VectorXcd eig_r = Eigen::EigenSolver<Eigen::MatrixXd>(Acl_r, false).eigenvalues();
  for (int i = 0; i < eig_r.size(); ++i)
    if (!(eig_r(i).real() < 0.0)) {
      res.status = CareResult::Status::Failed;
      res.message = "the computed solution does not stabilize the closed loop (eigenvalue " + fmt(eig_r(i)) + ")";
      return res;
    }
  res.P = V * P * V.transpose();
  res.P = 0.5 * (res.P + res.P.transpose()).eval();
  res.K = Rllt.solve(B.transpose() * res.P);
  res.closed_loop_eigenvalues = Eigen::EigenSolver<Eigen::MatrixXd>(A - B * res.K, false).eigenvalues();
  res.status = CareResult::Status::Solved;
  if (res.message.empty()) res.message = "solved";
  return res;
}

Eigen::MatrixXd vibration_weight(const FlexibleBody& body, double w_elastic, double w_rigid_pos,
                                 double w_rigid_rate) {
  for (const auto& [name, w] : {std::pair<const char*, double>{"w_elastic", w_elastic},
                                {"w_rigid_pos", w_rigid_pos},
                                {"w_rigid_rate", w_rigid_rate}})
    if (!(w >= 0.0) || !std::isfinite(w))
      throw std::invalid_argument(std::string("vibration_weight: ") + name + " = " + fmt(w) +
                                  ", must be finite and >= 0");
  const int n = body.n(), N = body.dofs();
  const ModalIntegrals& mi = body.integrals();
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(2 * N, 2 * N);
  Q.topLeftCorner(3, 3).diagonal().setConstant(w_rigid_pos);
  Q.block(3, 3, n, n) = w_elastic * mi.K;                 // strain energy, eq. 3.2
  Q.block(N, N, 3, 3).diagonal().setConstant(w_rigid_rate);
  Q.block(N + 3, N + 3, n, n) = w_elastic * mi.M;         // kinetic energy of q'
  return 0.5 * (Q + Q.transpose());
}

}  // namespace freeflex
