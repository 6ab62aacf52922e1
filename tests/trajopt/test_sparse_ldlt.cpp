// freeflex's sparse LDLᵀ (trajopt/sparse_ldlt.hpp) against dense eigen-solutions of random
// symmetric indefinite matrices, KKT (saddle-point) matrices among them: the inertia Ipopt
// needs, the solution, delayed and 2x2 pivots, singular matrices, storage that is too
// small; and its MA27 face (trajopt/ma27_bridge.hpp) called the way Ipopt calls it.
#include <catch2/catch.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <random>
#include <vector>

#include "trajopt/ma27_bridge.hpp"
#include "trajopt/sparse_ldlt.hpp"
#include "trajopt/sparse_ldlt_kernels.hpp"

using namespace freeflex::detail;

namespace {

/// A symmetric matrix given as 1-based triplets, each entry in either triangle or split
/// into two duplicates, and as a dense matrix.
struct Sparse {
  int n = 0;
  std::vector<int> rows, cols;
  std::vector<double> values;
  Eigen::MatrixXd dense;
};

void put(Sparse& s, int i, int j, double v, std::mt19937& rng) {
  s.dense(i, j) += v;
  if (i != j) s.dense(j, i) += v;
  const int how = std::uniform_int_distribution<int>(0, 2)(rng);
  if (how == 2) {  // a duplicate pair, summed by the solver
    s.rows.insert(s.rows.end(), {i + 1, j + 1});
    s.cols.insert(s.cols.end(), {j + 1, i + 1});
    s.values.insert(s.values.end(), {0.25 * v, 0.75 * v});
  } else {
    s.rows.push_back((how == 0 ? i : j) + 1);
    s.cols.push_back((how == 0 ? j : i) + 1);
    s.values.push_back(v);
  }
}

/// kind 0: random sparse, half the diagonals zero; kind 1: a KKT matrix [H Jᵀ; J 0] with
/// H sparse and indefinite (some zero diagonals) and J sparse with full row rank.
Sparse random_matrix(int kind, std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-1.0, 1.0), P(0.0, 1.0);
  Sparse s;
  s.n = std::uniform_int_distribution<int>(2, 70)(rng);
  s.dense = Eigen::MatrixXd::Zero(s.n, s.n);
  const double density = 0.03 + 0.3 * P(rng);
  const int nx = kind == 1 ? std::max(1, (2 * s.n) / 3) : s.n;
  for (int j = 0; j < nx; ++j)
    for (int i = j; i < nx; ++i)
      if (i == j ? P(rng) < 0.5 : P(rng) < density) put(s, i, j, U(rng), rng);
  for (int i = nx; i < s.n; ++i) {  // constraint rows: a diagonal-dominant entry keeps rank
    put(s, i, (i - nx) % nx, 1.0 + P(rng), rng);
    for (int j = 0; j < nx; ++j)
      if (P(rng) < density) put(s, i, j, U(rng), rng);
  }
  return s;
}

struct Solved {
  LdltFactorStatus status;
  Eigen::VectorXd x;
};

Solved factor_and_solve(const Sparse& m, double threshold, const Eigen::VectorXd& b) {
  const LdltSymbolic s = ldlt_analyse(m.n, static_cast<long long>(m.values.size()), m.rows.data(), m.cols.data(), 1);
  std::vector<double> a(static_cast<std::size_t>(4 * s.factor_doubles + 16));
  std::vector<int> iw(static_cast<std::size_t>(4 * s.factor_ints + 16));
  Solved r;
  r.status = ldlt_factor(s, m.values.data(), threshold, a.data(), static_cast<long long>(a.size()), iw.data(),
                         static_cast<long long>(iw.size()));
  r.x = b;
  if (r.status.code == LdltFactorStatus::Code::Ok) ldlt_solve(a.data(), iw.data(), r.x.data());
  return r;
}

}  // namespace

TEST_CASE("sparse LDLT: the inertia and the solution of random symmetric indefinite and KKT matrices",
          "[trajopt][ldlt]") {
  std::mt19937 rng(20261126);
  for (double threshold : {1e-8, 0.1}) {  // Ipopt's default ma27_pivtol, and a stable one
    int checked = 0, delayed = 0, blocks = 0;
    double worst = 0.0;
    for (int trial = 0; trial < 400; ++trial) {
      const Sparse m = random_matrix(trial % 2, rng);
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m.dense);
      const Eigen::VectorXd lambda = eig.eigenvalues();
      const double big = lambda.cwiseAbs().maxCoeff(), small = lambda.cwiseAbs().minCoeff();
      if (!(small > 1e-6 * big)) continue;  // near singular: the inertia is not a sharp question
      const Eigen::VectorXd b = Eigen::VectorXd::Random(m.n);
      const Solved r = factor_and_solve(m, threshold, b);
      REQUIRE(r.status.code == LdltFactorStatus::Code::Ok);
      const int negative = static_cast<int>((lambda.array() < 0.0).count());
      INFO("trial " << trial << ", n = " << m.n << ", threshold " << threshold);
      CHECK(r.status.negative == negative);
      // backward error ||A x - b|| / (||A|| ||x|| + ||b||)
      const double error = (m.dense * r.x - b).norm() / (m.dense.norm() * r.x.norm() + b.norm());
      worst = std::max(worst, error);
      ++checked;
      delayed += r.status.delayed;
      blocks += r.status.blocks_2x2;
    }
    INFO("threshold " << threshold << ": " << checked << " matrices, worst backward error " << worst << ", "
                      << delayed << " delayed pivots, " << blocks << " 2x2 pivots");
    CHECK(checked > 300);  // most random draws are well conditioned
    CHECK(delayed > 0);    // the delayed-pivot path is exercised
    CHECK(blocks > 0);     // and the 2x2 one
    // Threshold pivoting lets an entry grow by up to 1 + 1/threshold per pivot: the backward
    // error is bounded by about n eps / threshold (MA27's analysis), 70 x 2.2e-16 x 1e8 =
    // 1.6e-6 at Ipopt's 1e-8 (which relies on iterative refinement), 1.6e-13 at 0.1
    // (measured: 2.1e-9 and 8.9e-16).
    CHECK(worst < 70 * 2.3e-16 * (1.0 + 1.0 / threshold));
  }
}

TEST_CASE("sparse LDLT: a zero column is a singular matrix", "[trajopt][ldlt]") {
  std::mt19937 rng(7);
  Sparse m = random_matrix(1, rng);
  const int dead = m.n / 2;
  for (std::size_t t = 0; t < m.values.size(); ++t)
    if (m.rows[t] == dead + 1 || m.cols[t] == dead + 1) m.values[t] = 0.0;  // the pattern stays
  const Solved r = factor_and_solve(m, 1e-8, Eigen::VectorXd::Ones(m.n));
  CHECK(r.status.code == LdltFactorStatus::Code::Singular);
  CHECK(r.status.rank < m.n);
}

TEST_CASE("sparse LDLT: storage that is too small is asked for, then used", "[trajopt][ldlt]") {
  std::mt19937 rng(11);
  Sparse m;
  do m = random_matrix(1, rng);  // a nonsingular one
  while (!(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(m.dense).eigenvalues().cwiseAbs().minCoeff() > 1e-6));
  const LdltSymbolic s = ldlt_analyse(m.n, static_cast<long long>(m.values.size()), m.rows.data(), m.cols.data(), 1);
  std::vector<double> a(1);
  std::vector<int> iw(1);
  LdltFactorStatus st = ldlt_factor(s, m.values.data(), 1e-8, a.data(), 1, iw.data(), 1);
  REQUIRE(st.code == LdltFactorStatus::Code::NeedInts);
  iw.resize(static_cast<std::size_t>(st.need));
  st = ldlt_factor(s, m.values.data(), 1e-8, a.data(), 1, iw.data(), static_cast<long long>(iw.size()));
  REQUIRE(st.code == LdltFactorStatus::Code::NeedDoubles);
  a.resize(static_cast<std::size_t>(st.need));
  st = ldlt_factor(s, m.values.data(), 1e-8, a.data(), static_cast<long long>(a.size()), iw.data(),
                   static_cast<long long>(iw.size()));
  REQUIRE(st.code == LdltFactorStatus::Code::Ok);
  Eigen::VectorXd x = Eigen::VectorXd::Ones(m.n);
  ldlt_solve(a.data(), iw.data(), x.data());
  CHECK((m.dense * x - Eigen::VectorXd::Ones(m.n)).norm() < 1e-10 * m.dense.norm() * x.norm());  // round-off
}

TEST_CASE("sparse LDLT through MA27's interface, called as Ipopt calls it", "[trajopt][ldlt]") {
  const Ma27Routines ma27 = ma27_routines();
  std::mt19937 rng(3);
  std::vector<Sparse> cases = {random_matrix(1, rng), random_matrix(0, rng), random_matrix(1, rng)};
  Sparse diagonal;  // every variable its own supernode: the analysis is rebuilt from IKEEP
  diagonal.n = 5;
  diagonal.dense = Eigen::MatrixXd::Zero(5, 5);
  for (int i = 0; i < 5; ++i) put(diagonal, i, i, i % 2 ? -2.0 - i : 1.0 + i, rng);
  cases.push_back(diagonal);
  for (const Sparse& m : cases) {
    int n = m.n, nz = static_cast<int>(m.values.size());
    int icntl[30];
    double cntl[5];
    ma27.id(icntl, cntl);
    int liw = 2 * (2 * nz + 3 * n + 1), nsteps = 0, iflag = 0, info[20];
    std::vector<int> iw(liw), ikeep(3 * n), iw1(2 * n);
    double ops = 0.0;
    ma27.ad(&n, &nz, m.rows.data(), m.cols.data(), iw.data(), &liw, ikeep.data(), iw1.data(), &nsteps, &iflag, icntl,
            cntl, info, &ops);
    REQUIRE(info[0] == 0);
    // the sizes MA27AD recommends, without Ipopt's factor of 5, then grown as Ipopt grows them
    int la = std::max(nz, info[4]);
    liw = info[5];
    std::vector<double> a;
    int maxfrt = 0, tries = 0;
    cntl[0] = 1e-8;
    do {
      a.assign(la, 0.0);
      std::copy(m.values.begin(), m.values.end(), a.begin());
      iw.assign(liw, 0);
      ma27.bd(&n, &nz, m.rows.data(), m.cols.data(), a.data(), &la, iw.data(), &liw, ikeep.data(), &nsteps, &maxfrt,
              iw1.data(), icntl, cntl, info);
      if (info[0] == -3) liw = 2 * info[1];
      if (info[0] == -4) la = 2 * info[1];
    } while ((info[0] == -3 || info[0] == -4) && ++tries < 5);
    REQUIRE(info[0] == 0);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(m.dense);
    CHECK(info[14] == static_cast<int>((eig.eigenvalues().array() < 0.0).count()));
    Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0), b = x;
    std::vector<double> w(maxfrt);
    std::vector<int> iw1c(nsteps);
    ma27.cd(&n, a.data(), &la, iw.data(), &liw, w.data(), &maxfrt, x.data(), iw1c.data(), &nsteps, icntl, cntl);
    CHECK((m.dense * x - b).norm() < 1e-10 * (m.dense.norm() * x.norm()));  // round-off of a solve
  }
}

TEST_CASE("sparse LDLT kernels equal plain loops at every size and offset", "[trajopt][ldlt]") {
  // The register-blocked kernels have a main path and remainders in rows and columns; each
  // is compared with the definition at sizes 0 ... 21 (a block is 8 rows x 4 columns).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unif(-1.0, 1.0);
  auto random = [&](int r, int c) {
    Eigen::MatrixXd m(r, c);
    for (int j = 0; j < c; ++j)
      for (int i = 0; i < r; ++i) m(i, j) = unif(rng);
    return m;
  };
  double worst = 0.0;
  const bool portable = GENERATE(false, true);  // the CPU's kernels (AVX2 here), then SSE2
  use_portable_ldlt_kernels(portable);
  INFO((portable ? "SSE2 kernels" : "the CPU's kernels"));
  for (int rows = 0; rows <= 21; ++rows)
    for (int p = 0; p <= 9; ++p) {
      const Eigen::MatrixXd A = random(rows + 3, p), x = random(std::max(rows, p), 1);
      // y -= A x and the largest |y_i|, i >= 1
      Eigen::VectorXd y = random(rows, 1), ref = y - A.topRows(rows) * x.topRows(p);
      const double g = column_update_max(rows, p, A.data(), static_cast<int>(A.rows()), x.data(), y.data());
      worst = std::max(worst, rows ? (y - ref).cwiseAbs().maxCoeff() : 0.0);
      CHECK(g == Approx(rows > 1 ? ref.tail(rows - 1).cwiseAbs().maxCoeff() : 0.0).margin(1e-14));
      // y -= Aᵀ x
      Eigen::VectorXd z = random(p, 1), zref = z - A.topRows(rows).transpose() * x.topRows(rows);
      transposed_update(rows, p, A.data(), static_cast<int>(A.rows()), x.data(), z.data());
      worst = std::max(worst, p ? (z - zref).cwiseAbs().maxCoeff() : 0.0);
      // C -= L Wᵀ on the lower trapezoid
      for (int cols = 0; cols <= std::min(rows, 9); ++cols) {
        const Eigen::MatrixXd L = random(rows + 2, p), W = random(cols + 1, p);
        Eigen::MatrixXd C = random(rows + 1, cols), Cref = C;
        Cref.topRows(rows) -= L.topRows(rows) * W.topRows(cols).transpose();
        trapezoid_update(rows, cols, p, L.data(), static_cast<int>(L.rows()), W.data(), static_cast<int>(W.rows()),
                         C.data(), static_cast<int>(C.rows()));
        for (int j = 0; j < cols; ++j)
          for (int i = j; i <= rows; ++i) worst = std::max(worst, std::abs(C(i, j) - Cref(i, j)));
      }
    }
  use_portable_ldlt_kernels(false);
  INFO("largest difference " << worst);
  CHECK(worst < 1e-14);  // sums of at most 21 products of numbers below 1: rounding only, in another order
}
