// The three models against each other: the first-order model is the linearization of
// the full model (central differences), the zero-order model is the full model at q = 0.
#include <catch2/catch.hpp>

#include <random>

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "dynamics/full_model_kernel.hpp"
#include "support/bodies.hpp"
#include "support/fixed_trajectory.hpp"

using namespace freeflex;

namespace {

/// The rich beam and its four elements (tests/support/bodies.hpp).
FlexibleBody rich_body(int noa, std::vector<double> damping = {}, bool stiffening = false) {
  return FlexibleBody(Beam(freeflex_test::rich_beam()), noa, freeflex_test::rich_elements(), std::move(damping),
                      stiffening);
}

using freeflex_test::FixedTrajectory;

double max_rel(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / std::max(1e-300, b.cwiseAbs().maxCoeff());
}

}  // namespace

TEST_CASE("first-order A(t), B(t) match central differences of the full model", "[dynamics]") {
  // the paper's model and eq. 14.6 / 14.9 (geometric stiffening), each on the paper's basis
  // and on the finite-element basis (issue 15: stepped, hub, tip mass)
  const bool stiffening = GENERATE(false, true);
  const bool fe = GENERATE(false, true);
  const FlexibleBody body =
      fe ? FlexibleBody(Beam(freeflex_test::rich_beam()), 6,
                        BasisOptions{BasisOptions::Kind::FiniteElement, FiniteElementOptions{30, 5}},
                        freeflex_test::rich_elements(), {0.02, 0.01, 0.03}, stiffening)
         : rich_body(6, {0.02, 0.01, 0.03}, stiffening);
  INFO("basis " << body.basis().name() << ", geometric stiffening " << stiffening);
  REQUIRE(body.integrals().H_bar.cwiseAbs().maxCoeff() > (stiffening ? 0.01 : -1.0));
  REQUIRE(std::abs(body.integrals().S_o) > 0.05);
  const FullModel full(body);
  const int N = body.dofs(), ne = 4;
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 25; ++trial) {
    const RigidState s = freeflex_test::random_rigid_state(rng, U);
    Eigen::VectorXd u0(ne);
    for (int e = 0; e < ne; ++e) u0(e) = 2.0 * U(rng);
    const FixedTrajectory traj(s);
    const FirstOrderModel fo(body, traj, [&](const Instant&, Eigen::Ref<Eigen::VectorXd> u) { u = u0; }, {0, 1, 2, 3});
    const Instant at = Instant::at(0.37 * trial);
    const StateSpace ss = fo.state_space(at);
    const Eigen::MatrixXd &A = ss.A, &B = ss.B;

    Eigen::VectorXd z = Eigen::VectorXd::Zero(N), zd = z, zdd = z;
    z.head<3>() = s.pos;
    zd.head<3>() = s.vel;
    zdd.head<3>() = s.acc;
    const double h = 1e-6;  // central differences: truncation ~h^2, round-off ~eps/h ~1e-10
    Eigen::MatrixXd dz(N, N), dzd(N, N), dzdd(N, N), du(N, ne);
    for (int j = 0; j < N; ++j) {
      Eigen::VectorXd e = Eigen::VectorXd::Unit(N, j) * h;
      dz.col(j) = (full.residual(z + e, zd, zdd, u0) - full.residual(z - e, zd, zdd, u0)) / (2 * h);
      dzd.col(j) = (full.residual(z, zd + e, zdd, u0) - full.residual(z, zd - e, zdd, u0)) / (2 * h);
      dzdd.col(j) = (full.residual(z, zd, zdd + e, u0) - full.residual(z, zd, zdd - e, u0)) / (2 * h);
    }
    for (int k = 0; k < ne; ++k) {
      Eigen::VectorXd e = Eigen::VectorXd::Unit(ne, k) * h;
      du.col(k) = -(full.residual(z, zd, zdd, u0 + e) - full.residual(z, zd, zdd, u0 - e)) / (2 * h);
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(dzdd);
    Eigen::MatrixXd A_fd = Eigen::MatrixXd::Zero(2 * N, 2 * N), B_fd = Eigen::MatrixXd::Zero(2 * N, ne);
    A_fd.topRightCorner(N, N).setIdentity();
    A_fd.bottomLeftCorner(N, N) = llt.solve(-dz);
    A_fd.bottomRightCorner(N, N) = llt.solve(-dzd);
    B_fd.bottomRows(N) = llt.solve(du);
    const FirstOrderModel::Implicit imp = fo.implicit_form(at);
    const Eigen::VectorXd r0_direct = -full.residual(z, zd, zdd, u0);
    INFO("trial " << trial << ": A rel err " << max_rel(A, A_fd) << ", B rel err " << max_rel(B, B_fd));
    CHECK(max_rel(A, A_fd) < 1e-6);  // the bound; FD error measured <= 1.3e-7 (A), 1.4e-7 (B), either basis
    CHECK(max_rel(B, B_fd) < 1e-6);
    CHECK(max_rel(imp.r0, r0_direct) < 1e-12);  // same quantity, two code paths: round-off only
    CHECK(max_rel(imp.M0, dzdd) < 1e-8);         // residual is linear in z'': FD exact up to eps/h
  }
}

namespace {
/// A rigid motion that differs from instant to instant (the state is a smooth function of t).
class WavyTrajectory : public freeflex::RigidTrajectory {
 public:
  freeflex::RigidState at(const freeflex::Instant& w) const override {
    const double t = w.t;
    freeflex::RigidState s;
    s.pos << 0.3 * std::sin(t), -0.2 * t, 1.5 * std::sin(2.0 * t);
    s.vel << 0.3 * std::cos(t), -0.2, 3.0 * std::cos(2.0 * t);
    s.acc << -0.3 * std::sin(t), 0.0, -6.0 * std::sin(2.0 * t);
    return s;
  }
  double t_begin() const override { return 0.0; }
  double t_end() const override { return 10.0; }
  std::vector<double> breakpoints() const override { return {}; }
};
}  // namespace

TEST_CASE("first-order model: a reused workspace gives the bits of a fresh one", "[dynamics]") {
  // state_space() and implicit_form() write into the workspace's matrices from call to
  // call; nothing of an earlier instant may remain (exact equality: the same operations)
  const bool stiffening = GENERATE(false, true);
  const FlexibleBody body = rich_body(6, {0.02, 0.01, 0.03}, stiffening);
  const WavyTrajectory traj;
  const FirstOrderModel fo(body, traj,
                           [](const Instant& at, Eigen::Ref<Eigen::VectorXd> u) {
                             for (Eigen::Index e = 0; e < u.size(); ++e) u(e) = std::cos(at.t + e);
                           },
                           {0, 2});
  FirstOrderModel::Data reused = fo.create_data();
  for (int k = 0; k < 6; ++k) {
    const Instant at = Instant::at(0.7 * k);
    const StateSpace& a = fo.state_space(reused, at);
    const StateSpace b = fo.state_space(at);
    CHECK(a.A == b.A);
    CHECK(a.B == b.B);
    CHECK(a.g == b.g);
    const FirstOrderModel::Implicit fresh = fo.implicit_form(at);
    const FirstOrderModel::Implicit& again = fo.implicit_form(reused, at);
    CHECK(again.Kt == fresh.Kt);
    CHECK(again.Ct == fresh.Ct);
    CHECK(again.Gu == fresh.Gu);
    CHECK(again.r0 == fresh.r0);
    CHECK(again.M0 == fresh.M0);
  }
}

TEST_CASE("element forces: derivatives against central differences away from q = 0", "[dynamics]") {
  const bool stiffening = GENERATE(false, true);
  INFO("geometric stiffening " << stiffening);
  const FlexibleBody body = rich_body(8, {}, stiffening);
  const int N = body.dofs(), n = body.n();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    const double th = 3.0 * U(rng);
    Eigen::VectorXd q(n);
    for (int i = 0; i < n; ++i) q(i) = 0.05 * U(rng);
    for (int e = 0; e < 4; ++e) {
      const Eigen::MatrixXd d = body.element_force_derivative(e, th, q).derivative;
      Eigen::MatrixXd d_fd(N, 1 + n);
      const double h = 1e-6;  // central differences of smooth trigonometric terms
      d_fd.col(0) = (body.element_force(e, th + h, q) - body.element_force(e, th - h, q)) / (2 * h);
      for (int j = 0; j < n; ++j) {
        const Eigen::VectorXd dq = Eigen::VectorXd::Unit(n, j) * h;
        d_fd.col(1 + j) = (body.element_force(e, th, q + dq) - body.element_force(e, th, q - dq)) / (2 * h);
      }
      INFO("element " << e << " trial " << trial);
      // central differences: h² f''' ~ 1e-12 truncation, eps/h ~ 1e-10 round-off (measured 2e-10)
      CHECK((d - d_fd).cwiseAbs().maxCoeff() < 1e-7 * std::max(1.0, d.cwiseAbs().maxCoeff()));
    }
  }
}

TEST_CASE("zero-order model is the full model's rigid rows at q = 0", "[dynamics]") {
  const bool stiffening = GENERATE(false, true);
  const FlexibleBody body = rich_body(4, {}, stiffening);
  const FullModel full(body);
  const ZeroOrderModel zero(body);
  const int N = body.dofs();
  Eigen::VectorXd x0(6);
  x0 << 0.2, -0.4, 1.1, 0.3, 0.5, -2.0;
  Eigen::VectorXd u(4);
  u << 0.7, -1.2, 0.4, 0.9;
  const Eigen::Vector3d acc = zero.acceleration(x0, u);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(N), zd = z, zdd = z;
  z.head<3>() = x0.head<3>();
  zd.head<3>() = x0.tail<3>();
  zdd.head<3>() = acc;
  // rigid rows of the full residual vanish to round-off of O(1) terms
  CHECK(full.residual(z, zd, zdd, u).head<3>().cwiseAbs().maxCoeff() < 1e-13);
}

TEST_CASE("full model: rhs solves the residual, damping leaves rigid motion alone", "[dynamics]") {
  const bool stiffening = GENERATE(false, true);  // rank-two and rank-four Woodbury
  INFO("geometric stiffening " << stiffening);
  const FlexibleBody body = rich_body(6, {0.05, 0.05}, stiffening);
  const FullModel full(body);
  auto data = full.create_data();
  const int N = body.dofs();
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(2 * N, -0.3, 0.4), u(4);
  u << 0.5, 0.1, -0.3, 0.2;
  REQUIRE(full.rhs(data, x, u));
  const Eigen::VectorXd& xd = data.x_dot;
  const double res = full.residual(x.head(N), x.tail(N), xd.tail(N), u).cwiseAbs().maxCoeff();
  const double scale = (body.integrals().K * x.segment(3, body.n())).cwiseAbs().maxCoeff();
  INFO("residual " << res << " against stiffness forces of " << scale);
  CHECK(res < 1e-13 * scale);  // a linear solve with condition number ~1e2: round-off of the largest term
  // rhs factors the rest mass matrix once and corrects for q and θ (rank two, Woodbury):
  // exact at any state, which random states with large q and θ check
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    for (int i = 0; i < 2 * N; ++i) x(i) = U(rng);
    x(2) *= 4.0;  // θ across the circle
    REQUIRE(full.rhs(data, x, u));
    const Eigen::VectorXd r = full.residual(x.head(N), x.tail(N), xd.tail(N), u);
    // the largest terms: stiffness forces and inertia forces (|𝕄| |z''|, large where the
    // stiffened 𝕄 at these O(1) q is nearly singular)
    const Eigen::MatrixXd Mz = body.mass_matrix(x(2), x.segment(3, body.n()));
    const double sc = std::max((body.integrals().K * x.segment(3, body.n())).cwiseAbs().maxCoeff(),
                               (Mz.cwiseAbs() * xd.tail(N).cwiseAbs()).maxCoeff());
    INFO("trial " << trial << ": residual " << r.cwiseAbs().maxCoeff() << " against " << sc << ", cond(M) "
                  << Mz.jacobiSvd().singularValues()(0) / Mz.jacobiSvd().singularValues()(N - 1));
    CHECK(r.cwiseAbs().maxCoeff() < 1e-13 * sc);  // same bound as above
  }
  Eigen::VectorXd rigid = Eigen::VectorXd::Zero(N);
  rigid.head<3>() << 0.7, -0.2, 1.3;  // any rigid velocity
  CHECK((body.damping() * rigid).cwiseAbs().maxCoeff() < 1e-12);  // round-off of 𝕄0 V products
}

TEST_CASE("first-order rhs (term by term) equals A x1 + B u1 + g", "[dynamics]") {
  const bool stiffening = GENERATE(false, true);
  const FlexibleBody body = rich_body(6, {0.02, 0.01}, stiffening);
  const int N = body.dofs(), ne = 4;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    const RigidState s = freeflex_test::random_rigid_state(rng, U);
    Eigen::VectorXd u0(ne), u1(3), x1(2 * N);
    for (int e = 0; e < ne; ++e) u0(e) = U(rng);
    for (int k = 0; k < 3; ++k) u1(k) = U(rng);
    for (int i = 0; i < 2 * N; ++i) x1(i) = 0.1 * U(rng);
    const FixedTrajectory traj(s);
    const FirstOrderModel fo(body, traj, [&](const Instant&, Eigen::Ref<Eigen::VectorXd> u) { u = u0; }, {1, 2, 3});
    FirstOrderModel::Data data = fo.create_data();
    const StateSpace ss = fo.state_space(data, Instant::at(0.0));
    const Eigen::MatrixXd& A = ss.A;
    const Eigen::VectorXd fast = fo.rhs(data, Instant::at(0.0), x1, u1);
    const Eigen::VectorXd slow = A * x1 + ss.B * u1 + ss.g;
    // two evaluation orders of the same sums: round-off relative to the largest term
    CHECK((fast - slow).cwiseAbs().maxCoeff() < 1e-11 * (A.cwiseAbs() * x1.cwiseAbs()).maxCoeff());
  }
}

TEST_CASE("a body on a caller's basis is the body on that basis, and no basis is an error", "[dynamics]") {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  const std::vector<ForceElement> torque{{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}};
  const FlexibleBody named(beam, 6, torque, {0.01});
  const FlexibleBody given(beam, make_basis(beam, 6, BasisOptions{}), torque, {0.01});
  // the same functions, integrals and forces: the same numbers, bit for bit
  CHECK(given.n() == 6);
  CHECK(given.integrals().M == named.integrals().M);
  CHECK(given.integrals().K == named.integrals().K);
  CHECK(given.damping() == named.damping());
  const Eigen::VectorXd q = Eigen::VectorXd::LinSpaced(6, -0.1, 0.2);
  CHECK(given.element_force(0, 0.3, q) == named.element_force(0, 0.3, q));
  CHECK_THROWS_WITH(FlexibleBody(beam, std::shared_ptr<const ShapeBasis>(), torque), Catch::Contains("no shape basis"));
}

namespace {
/// f(model, x, u, a, b) at 200 random states and commands of rich_body(n) (rigid
/// coordinates and rates up to 3, elastic ones up to 0.05), with two workspaces.
template <class F>
void at_random_states(int n, unsigned seed, F&& f) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const FlexibleBody body = rich_body(n, {0.01, 0.02});
  const FullModel model(body);
  FullModel::Data a = model.create_data(), b = model.create_data();
  const int N = body.dofs();
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::VectorXd x(2 * N), u(body.elements().size());
    for (int i = 0; i < 2 * N; ++i) x(i) = U(gen) * (i < 3 || (i >= N && i < N + 3) ? 3.0 : 0.05);
    for (int e = 0; e < u.size(); ++e) u(e) = U(gen);
    INFO("n = " << n << ", trial " << trial);
    f(model, x, u, a, b);
  }
}
}  // namespace

TEST_CASE("the full model's kernels for fixed sizes give the run-time kernel's numbers", "[dynamics]") {
  // FullModel::rhs compiles its loops for 4, 6, 8, 10 and 20 elastic coordinates; with
  // the same operations in the same order they must give the same bits as the kernel of
  // run-time size (the paper designs' CSVs depend on it). A build with -march (FMA, wider
  // vectors) may round differently: there the bound is round-off (1e-12 relative).
#if defined(__FMA__) || defined(__AVX__)
  const double tol = 1e-12;  // vectorized and fused code rounds differently
#else
  const double tol = 0.0;  // same operations, same order: same bits
#endif
  for (int n : {4, 6, 8, 10, 20})
    at_random_states(n, 7, [&](const FullModel& model, const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                               FullModel::Data& a, FullModel::Data& b) {
      REQUIRE(model.rhs(a, x, u));
      REQUIRE(detail::full_rhs_runtime_size(model, b, x, u));
      const double scale = b.x_dot.cwiseAbs().maxCoeff();
      CHECK((a.x_dot - b.x_dot).cwiseAbs().maxCoeff() <= tol * scale);
    });
}

TEST_CASE("the full model's split sums agree with the sequential ones to round-off", "[dynamics]") {
  // The sizes without a kernel of their own (NOA 20, 13) sum M q, K q, 𝕄_b(0)⁻¹ g and the
  // dot products in a split order with shorter chains; the same terms, so only round-off
  // may differ: 1e-12 of the largest entry (measured: 4e-16 at most over these states).
  double worst = 0.0;
  for (int n : {20, 13})
    at_random_states(n, 5, [&](const FullModel& model, const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                               FullModel::Data& a, FullModel::Data& b) {
      REQUIRE(model.rhs(a, x, u));
      REQUIRE(detail::full_rhs_sequential(model, b, x, u));
      const double scale = b.x_dot.cwiseAbs().maxCoeff();
      const double diff = (a.x_dot - b.x_dot).cwiseAbs().maxCoeff();
      worst = std::max(worst, diff / scale);
      CHECK(diff <= 1e-12 * scale);
    });
  CHECK(worst > 0.0);  // the orders do differ: the split sums are in use
  WARN("largest relative difference " << worst);
}

TEST_CASE("the full model's AVX-512 variant gives the bits of the AVX2 or baseline one", "[dynamics]") {
  // NOA 20 and the run-time size (13) run with 512-bit vectors where the processor has
  // AVX-512; with no fused multiply-add (the rotations are kept from fusing, which GCC did
  // there whatever -ffp-contract said) the numbers must be those of the other variants.
  if (!detail::full_rhs_avx512_available()) {
    WARN("no AVX-512 on this processor: the variant is not compared");
    return;
  }
  for (int n : {20, 13})
    at_random_states(n, 11, [&](const FullModel& model, const Eigen::VectorXd& x, const Eigen::VectorXd& u,
                                FullModel::Data& a, FullModel::Data& b) {
      REQUIRE(detail::full_rhs_large(model, a, x, u, true));
      REQUIRE(detail::full_rhs_large(model, b, x, u, false));
      CHECK(a.x_dot == b.x_dot);  // same operations in the same order: same bits
    });
}

TEST_CASE("one workspace serves the first-order state space at every instant and input count", "[dynamics]") {
  // state_space(data, at) rewrites all of A, B, g each call: a workspace reused across
  // models with other inputs, or whose matrices a caller changed, gives a fresh one's answer
  const FlexibleBody body = rich_body(6, {0.02});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const FixedTrajectory traj(freeflex_test::random_rigid_state(rng, U));
  const auto nominal = [](const Instant&, Eigen::Ref<Eigen::VectorXd> u) { u.setConstant(0.3); };
  const FirstOrderModel two(body, traj, nominal, {1, 2});
  const FirstOrderModel three(body, traj, nominal, {0, 1, 3});
  FirstOrderModel::Data data = two.create_data();
  for (int trial = 0; trial < 4; ++trial) {
    const FirstOrderModel& model = trial % 2 ? three : two;
    const Instant at = Instant::at(0.21 * trial);
    data.state_space.A.setConstant(7.0);  // a caller's scribbles
    data.state_space.B.setConstant(7.0);
    data.state_space.g.setConstant(7.0);
    const StateSpace& reused = model.state_space(data, at);
    const StateSpace fresh = model.state_space(at);
    CHECK(reused.A == fresh.A);
    CHECK(reused.B == fresh.B);
    CHECK(reused.g == fresh.g);
  }
}
