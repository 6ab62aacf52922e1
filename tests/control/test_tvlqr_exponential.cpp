// The exponential sweep of the TV-LQR (TvlqrOptions::Method::Exponential): its
// φ-functions against an independent computation (Eigen's Padé matrix exponential of the
// augmented operator), and its laws against closed forms and against the BDF sweep on
// the same problems (scalar Riccati, a forced LTV system with a breakpoint, the paper's
// moment example, the beam at rest with a fallback to BDF), the choice of Auto, and its
// work budget.
#include <catch2/catch.hpp>

#include <cmath>
#include <iostream>
#include <memory>
#include <random>

#include <unsupported/Eigen/KroneckerProduct>
#include <unsupported/Eigen/MatrixFunctions>

#include "control/phi_functions.hpp"
#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/lqr.hpp"
#include "freeflex/control/tvlqr.hpp"
#include "freeflex/sim/simulate.hpp"
#include "support/bodies.hpp"
#include "support/moment_case.hpp"
#include "support/systems.hpp"

using namespace freeflex;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using Method = TvlqrOptions::Method;

namespace {

/// φ_0..φ_kmax of the square matrix A by one matrix exponential of the augmented matrix
/// [[A, I, 0..], [0, 0, I, ..], .., [0 .. 0]], whose first block row is φ_0(A) .. φ_k(A).
std::vector<Eigen::MatrixXd> phi_by_expm(const Eigen::MatrixXd& A, int kmax) {
  const int n = static_cast<int>(A.rows());
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n * (kmax + 1), n * (kmax + 1));
  M.topLeftCorner(n, n) = A;
  for (int k = 0; k < kmax; ++k) M.block(k * n, (k + 1) * n, n, n).setIdentity();
  const Eigen::MatrixXd E = M.exp();
  std::vector<Eigen::MatrixXd> out;
  for (int k = 0; k <= kmax; ++k) out.push_back(E.block(0, k * n, n, n));
  return out;
}

/// A trace-free 2x2 N = [[n00, n01], [n10, −n00]] with det N = det.
Eigen::Matrix2d trace_free(double n00, double n01, double det) {
  // det = −n00² − n01 n10
  const double n10 = -(det + n00 * n00) / n01;
  Eigen::Matrix2d N;
  N << n00, n01, n10, -n00;
  return N;
}

/// The operator X ↦ c X + N_Iᵀ X + X N_J on column-major vec(X), and its parts.
struct PairOperator {
  Eigen::Matrix4d P, Q, L;
  PairOperator(double c, const Eigen::Matrix2d& Ni, const Eigen::Matrix2d& Nj) {
    const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
    P = Eigen::kroneckerProduct(I, Ni.transpose());  // vec(Nᵢᵀ X) = (I ⊗ Nᵢᵀ) vec X
    Q = Eigen::kroneckerProduct(Nj.transpose(), I);  // vec(X Nⱼ) = (Nⱼᵀ ⊗ I) vec X
    L = c * Eigen::Matrix4d::Identity() + P + Q;
  }
};

struct LtvCase {
  LtvSystem sys;
  Eigen::MatrixXd Q, R;
  TvlqrOptions options;
};

/// The forced system (support/systems.hpp) with its weights and tight tolerances.
LtvCase forced_case() {
  LtvCase c;
  c.sys = freeflex_test::forced_system();
  c.Q = Eigen::Matrix2d::Identity() * 3.0;
  c.R = Eigen::MatrixXd::Constant(1, 1, 0.2);
  c.options.Qf = Eigen::Matrix2d::Identity() * 5.0;
  c.options.rtol = 1e-10;
  c.options.atol = 1e-12;
  c.options.grid_step_s = 0.01;
  return c;
}

struct LawDifference {
  double gain = 0.0, feedforward = 0.0, feedforward_scale = 0.0, cost = 0.0;
};

LawDifference difference(const TvlqrResult& a, const TvlqrResult& b) {
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  REQUIRE(a.t == b.t);
  LawDifference d;
  for (std::size_t i = 0; i < a.t.size(); ++i) {
    d.gain = std::max(d.gain, (a.K[i] - b.K[i]).norm() / b.K[i].norm());
    d.feedforward = std::max(d.feedforward, (a.feedforward.row(i) - b.feedforward.row(i)).norm());
  }
  d.feedforward_scale = b.feedforward.cwiseAbs().maxCoeff();
  d.cost = std::abs(a.c0 - b.c0) / std::max(std::abs(b.c0), 1e-300);
  return d;
}

using freeflex_test::MomentCase;

}  // namespace

TEST_CASE("φ-functions at complex z agree with the augmented matrix exponential", "[control][exponential]") {
  // z on both sides of the series radius (|z| = 1), near 0, and far out in both half planes
  const std::complex<double> zs[] = {{1e-6, 0.0}, {0.3, -0.4}, {-0.9, 0.2}, {1.1, 0.5}, {-7.0, 30.0}, {-250.0, 4.0},
                                     {3.0, -2.0}};
  for (const auto z : zs) {
    Eigen::Matrix2d A;  // the real 2x2 representation of z
    A << z.real(), -z.imag(), z.imag(), z.real();
    const auto ref = phi_by_expm(A, detail::kMaxPhi);
    std::complex<double> phi[detail::kMaxPhi + 1];
    detail::phi_values(z, detail::kMaxPhi, phi);
    for (int k = 0; k <= detail::kMaxPhi; ++k) {
      const std::complex<double> r(ref[k](0, 0), ref[k](1, 0));
      INFO("z = " << z << ", k = " << k << ": " << phi[k] << " against " << r);
      CHECK(std::abs(phi[k] - r) <= 1e-12 * std::max(1.0, std::abs(r)));  // expm's Padé error ~1e-15 relative
    }
  }
}

TEST_CASE("φ-functions of the block operators agree with the matrix exponential of the operator",
          "[control][exponential]") {
  // Pairs of 2x2 blocks with complex (det > 0), real (det < 0) and near-defective (|det| tiny:
  // the Taylor branch) eigenvalues, and 1x1 blocks; X ↦ c X + N_Iᵀ X + X N_J at step t.
  struct Pair {
    double c, det_i, det_j;
    int size_i, size_j;
  };
  const Pair pairs[] = {{-3.0, 400.0, 2500.0, 2, 2},  {-0.5, -4.0, 9.0, 2, 2},     {-0.5, 9.0, -4.0, 2, 2},
                        {-1.5, -4.0, -9.0, 2, 2},    {-20.0, 1e-14, 900.0, 2, 2}, {-1.0, 1e-12, -1e-13, 2, 2},
                        {-2.0, 0.0, 100.0, 1, 2},    {-40.0, 0.0, 0.0, 1, 1},     {0.7, 36.0, 36.0, 2, 2}};
  const double t = 0.05;
  for (const Pair& p : pairs) {
    const Eigen::Matrix2d Ni = p.size_i == 2 ? trace_free(0.3, 1.7, p.det_i) : Eigen::Matrix2d::Zero();
    const Eigen::Matrix2d Nj = p.size_j == 2 ? trace_free(-0.8, -2.1, p.det_j) : Eigen::Matrix2d::Zero();
    const PairOperator op(p.c, Ni, Nj);
    const auto ref = phi_by_expm(t * op.L, detail::kMaxPhi);
    detail::PairCoefficients co;
    detail::pair_phi(t, p.c, p.det_i, p.size_i, p.det_j, p.size_j, detail::kMaxPhi, co);
    for (int k = 0; k <= detail::kMaxPhi; ++k) {
      const auto& a = co.a[k];
      const Eigen::Matrix4d f = a[0] * Eigen::Matrix4d::Identity() + a[1] * op.P + a[2] * op.Q + a[3] * op.P * op.Q;
      const double err = (f - ref[k]).norm() / ref[k].norm();
      INFO("c = " << p.c << ", det " << p.det_i << ", " << p.det_j << ", k = " << k << ": relative error " << err);
      CHECK(err < 1e-11);  // the Taylor branch's truncation ~1e-12 (phi_functions.cpp), expm ~1e-15
    }
    // one block, vectors transformed by f(t(m + Nᵀ))
    const Eigen::Matrix2d Lb = p.c * Eigen::Matrix2d::Identity() + Ni.transpose();
    const auto refb = phi_by_expm(t * Lb, detail::kMaxPhi);
    detail::BlockCoefficients cb;
    detail::block_phi(t, p.c, p.det_i, p.size_i, detail::kMaxPhi, cb);
    for (int k = 0; k <= detail::kMaxPhi; ++k) {
      const Eigen::Matrix2d f = cb.a[k][0] * Eigen::Matrix2d::Identity() + cb.a[k][1] * Ni.transpose();
      if (p.size_i == 1) {
        CHECK(std::abs(f(0, 0) - refb[k](0, 0)) < 1e-12 * std::abs(refb[k](0, 0)));  // only (0,0) is the block
      } else {
        CHECK((f - refb[k]).norm() < 1e-11 * refb[k].norm());  // as above
      }
    }
  }
}

TEST_CASE("TV-LQR exponential sweep: scalar Riccati closed form", "[control][exponential]") {
  // As in test_lqr.cpp: x' = a x + b u, the closed form of P(τ).
  const double a = 0.7, b = 1.3, q = 2.0, r = 0.5, pf = 3.0, T = 1.5;
  const LtvSystem sys = freeflex_test::scalar_system(a, b);
  TvlqrOptions o;
  o.method = Method::Exponential;
  o.Qf = Eigen::MatrixXd::Constant(1, 1, pf);
  o.rtol = 1e-11;
  o.atol = 1e-13;
  o.store_riccati = true;
  const TvlqrResult res = solve_tvlqr(sys, 0.0, T, Eigen::MatrixXd::Constant(1, 1, q), Eigen::MatrixXd::Constant(1, 1, r), o);
  REQUIRE(res.ok());
  CHECK(res.method == Method::Exponential);
  const double k = b * b / r, disc = std::sqrt(a * a + k * q);
  const double pp = (a + disc) / k, pm = (a - disc) / k;
  double worst = 0.0;
  for (std::size_t i = 0; i < res.t.size(); ++i) {
    const double tau = T - res.t[i];
    const double e = (pf - pp) / (pf - pm) * std::exp(-k * (pp - pm) * tau);
    const double p = (pp - e * pm) / (1.0 - e);
    worst = std::max(worst, std::abs(res.P[i](0, 0) - p) / p);
  }
  INFO("max relative error of P over the grid: " << worst << " (" << res.steps << " steps, " << res.rejected_steps
                                                  << " rejected)");
  // rtol 1e-11 per step: measured 4.8e-12 over the grid (2.6e-7 before the error of the dense
  // output inside a step, where Gauss collocation is not superconvergent, was estimated)
  CHECK(worst < 1e-10);
  CHECK(res.fallback_steps == 0);
}

TEST_CASE("TV-LQR exponential and BDF sweeps agree on a forced LTV system with a breakpoint",
          "[control][exponential]") {
  LtvCase c = forced_case();
  c.options.method = Method::Bdf;
  const TvlqrResult bdf = solve_tvlqr(c.sys, 0.0, 2.0, c.Q, c.R, c.options);
  c.options.method = Method::Exponential;
  const TvlqrResult ex = solve_tvlqr(c.sys, 0.0, 2.0, c.Q, c.R, c.options);
  const LawDifference d = difference(ex, bdf);
  INFO("gain " << d.gain << ", feedforward " << d.feedforward << " of " << d.feedforward_scale << ", c0 " << d.cost
               << "; steps exponential " << ex.steps << ", BDF " << bdf.steps);
  CHECK(ex.method == Method::Exponential);
  CHECK(bdf.method == Method::Bdf);
  CHECK(d.gain < 1e-7);                                 // both to rtol 1e-10: differences ~1e-9
  CHECK(d.feedforward < 1e-7 * d.feedforward_scale);    // same
  CHECK(d.cost < 1e-7);                                 // same
  CHECK(d.feedforward_scale > 0.1);                     // the forcing is felt
  CHECK((ex.P0 - bdf.P0).norm() < 1e-8 * bdf.P0.norm());  // same
}

TEST_CASE("TV-LQR exponential sweep on the moment example: the BDF law in far fewer steps",
          "[control][exponential]") {
  const MomentCase c(6);
  REQUIRE(c.pert.total.ok());
  TvlqrOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.grid_step_s = 0.01;
  o.method = Method::Bdf;
  const TvlqrResult bdf = solve_tvlqr(*c.model, 0.0, 3.0, c.Q, c.R, o);
  o.method = Method::Exponential;
  const TvlqrResult ex = solve_tvlqr(*c.model, 0.0, 3.0, c.Q, c.R, o);
  const LawDifference d = difference(ex, bdf);
  std::cout << "[control] moment example NOA 6: exponential " << ex.steps << " steps (" << ex.rejected_steps
            << " rejected, " << ex.fallback_steps << " by BDF), BDF " << bdf.steps << "; gain difference " << d.gain
            << ", feedforward " << d.feedforward / d.feedforward_scale << " relative, c0 " << d.cost << "\n";
  // Against a BDF reference at rtol 1e-12 (bench/tvlqr_accuracy) BDF at 1e-10 is off by 5e-7
  // in K and 1.4e-4 in u_ff, the exponential sweep by 1e-7 and 1e-6: their difference is BDF's.
  CHECK(d.gain < 2e-6);
  CHECK(d.feedforward < 5e-4 * d.feedforward_scale);
  CHECK(d.cost < 5e-4);
  CHECK(ex.steps * 5 < bdf.steps);  // measured 126 against 1077 at NOA 6
  // The closed loops of the two laws on the first-order model leave the same vibration.
  ClosedLoopOptions co;
  co.t_end = 3.0;
  co.output_step_s = 0.01;
  co.integrator.rtol = 1e-10;
  co.integrator.atol = 1e-12;
  const ClosedLoopResult rb = simulate_closed_loop_first_order(*c.model, bdf, {}, co);
  const ClosedLoopResult re = simulate_closed_loop_first_order(*c.model, ex, {}, co);
  REQUIRE(rb.ok());
  REQUIRE(re.ok());
  const Eigen::MatrixXd qb = rb.z.rightCols(6), qe = re.z.rightCols(6);  // the elastic coordinates
  const double dx = (qb - qe).cwiseAbs().maxCoeff(), scale = qb.cwiseAbs().maxCoeff();
  INFO("closed-loop state difference " << dx << " of " << scale);
  CHECK(dx < 1e-4 * scale);  // the feedforward's 1.4e-4 difference (BDF's error) bounds it
}

TEST_CASE("TV-LQR Auto: BDF below 24 states, the exponential sweep from 24", "[control][exponential]") {
  for (int noa : {6, 10}) {
    const MomentCase c(noa);
    REQUIRE(c.pert.total.ok());
    TvlqrOptions o;
    o.grid_step_s = 0.05;
    const TvlqrResult law = solve_tvlqr(*c.model, 0.0, 3.0, c.Q, c.R, o);
    REQUIRE(law.ok());
    const int n = c.model->state_size();
    CHECK(n == 2 * (3 + noa));
    CHECK(law.method == (n >= TvlqrOptions::kAutoExponentialStates ? Method::Exponential : Method::Bdf));
    if (noa == 10) {
      o.method = Method::Bdf;
      const TvlqrResult bdf = solve_tvlqr(*c.model, 0.0, 3.0, c.Q, c.R, o);
      const LawDifference d = difference(law, bdf);
      std::cout << "[control] moment example NOA 10 at the default tolerances: exponential " << law.steps
                << " steps, BDF " << bdf.steps << "; gain difference " << d.gain << ", feedforward "
                << d.feedforward / d.feedforward_scale << " relative\n";
      CHECK(d.gain < 1e-4);                               // BDF at rtol 1e-8 is off by ~1e-5 at NOA 20 (its own error)
      CHECK(d.feedforward < 1e-2 * d.feedforward_scale);  // BDF's u_ff error, 7e-3 at NOA 20
      CHECK(law.steps * 10 < bdf.steps);
    }
  }
}

TEST_CASE("TV-LQR exponential sweep from Qf = 0 on the beam at rest: BDF where the loop has no form, the CARE gain",
          "[control][exponential]") {
  const FlexibleBody body = freeflex_test::actuated_beam(4);
  const freeflex_test::RestTrajectory rest(0.4);
  const FirstOrderModel model(body, rest, freeflex_test::no_commands(), {0, 1, 2});
  const Eigen::MatrixXd Q = vibration_weight(body, 1.0, 100.0, 10.0);
  const Eigen::MatrixXd R = Eigen::Vector3d(1.0, 0.25, 0.25).asDiagonal();
  const StateSpace ss = model.state_space(Instant::at(0.0));
  CareOptions cop;
  cop.restrict_to_controllable = true;
  const CareResult care = solve_care(ss.A, ss.B, Q, R, cop);
  REQUIRE(care.ok());
  TvlqrOptions o;
  o.method = Method::Exponential;
  o.Qf = Eigen::MatrixXd::Zero(Q.rows(), Q.cols());  // P ≈ 0 near tf: the free body's rigid double integrators
  o.rtol = 1e-10;
  o.atol = 1e-12;
  o.grid_step_s = 0.5;
  const TvlqrResult law = solve_tvlqr(model, 0.0, 25.0, Q, R, o);
  REQUIRE(law.ok());
  const double err0 = (law.K.front() - care.K).norm() / care.K.norm();
  std::cout << "[control] beam at rest, exponential sweep: " << law.steps << " steps, " << law.fallback_steps
            << " taken by BDF; gain at t0 vs CARE " << err0 << "\n";
  CHECK(law.fallback_steps > 0);  // the closed loop at P = 0 has no well-conditioned eigenbasis
  CHECK(err0 < 1e-6);             // as the BDF sweep (test_lqr.cpp)
  // P0 turned back from the frame at θ0 = 0.4 rad: against the BDF sweep's P0
  o.method = Method::Bdf;
  const TvlqrResult bdf = solve_tvlqr(model, 0.0, 25.0, Q, R, o);
  REQUIRE(bdf.ok());
  INFO("|P0 - P0_bdf| / |P0_bdf| = " << (law.P0 - bdf.P0).norm() / bdf.P0.norm());
  CHECK((law.P0 - bdf.P0).norm() < 1e-7 * bdf.P0.norm());  // both to rtol 1e-10 over a converged sweep
}

TEST_CASE("TV-LQR exponential sweep: a work budget stops it with the time reached", "[control][exponential][issue20]") {
  LtvCase c = forced_case();
  c.options.method = Method::Exponential;
  const TvlqrResult free = solve_tvlqr(c.sys, 0.0, 2.0, c.Q, c.R, c.options);
  REQUIRE(free.ok());
  REQUIRE(free.steps > 4);
  const long long step = 16 * riccati_step_work(2);  // one exponential step
  c.options.budget = std::make_shared<WorkBudget>(3 * step, "the test");
  const TvlqrResult stopped = solve_tvlqr(c.sys, 0.0, 2.0, c.Q, c.R, c.options);
  CHECK(stopped.status == TvlqrResult::Status::IntegrationFailed);
  CHECK(stopped.steps + stopped.rejected_steps == 3);
  CHECK_THAT(stopped.message, StartsWith("stopped at t = ") && Contains("the test's work budget"));
  CHECK(c.options.budget->exhausted());
}

TEST_CASE("TV-LQR exponential sweep: a model that throws ends it as a failure with the time", "[control][exponential]") {
  LtvCase c = forced_case();
  const auto inner = c.sys.state_space;
  c.sys.state_space = [inner](const Instant& at) {
    if (at.t < 0.5) throw std::runtime_error("no model before 0.5 s");
    return inner(at);
  };
  c.options.method = Method::Exponential;
  const TvlqrResult r = solve_tvlqr(c.sys, 0.0, 2.0, c.Q, c.R, c.options);
  CHECK(r.status == TvlqrResult::Status::IntegrationFailed);
  CHECK_THAT(r.message, Contains("no model before 0.5 s") && Contains("t = "));
}
