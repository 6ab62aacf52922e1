// ElasticDynamics and ManeuverDynamics (trajopt/elastic_dynamics.hpp, maneuver_dynamics.hpp):
// the body-axes first-order model against the inertial FirstOrderModel (another
// derivation and code path), the stiffening terms against their formula, and the
// analytic first and second derivatives against central differences, with non-zero
// synthetic H_bar and G_c.
#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <vector>

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/trajopt/maneuver_dynamics.hpp"
#include "support/bodies.hpp"

using namespace freeflex;

namespace {

FlexibleBody rich_damped_body() {
  return FlexibleBody(Beam(freeflex_test::rich_beam()), 4, freeflex_test::rich_elements(), {0.02, 0.05, 0.01});
}

/// One rigid state held at t = 0 (what FirstOrderModel reads from its nominal motion).
class FrozenTrajectory : public RigidTrajectory {
 public:
  explicit FrozenTrajectory(RigidState s) : s_(std::move(s)) {}
  RigidState at(const Instant&) const override { return s_; }
  double t_begin() const override { return 0.0; }
  double t_end() const override { return 1.0; }
  std::vector<double> breakpoints() const override { return {}; }

 private:
  RigidState s_;
};

Eigen::Matrix2d rot(double th) {
  Eigen::Matrix2d C;
  C << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
  return C;
}

ElasticDynamics::Stiffening synthetic_stiffening(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Eigen::MatrixXd A(n, n), B(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = U(rng), B(i, j) = U(rng);
  return {A + A.transpose(), B + B.transpose()};
}

}  // namespace

TEST_CASE("body-axes elastic dynamics equal the inertial first-order model", "[trajopt]") {
  const FlexibleBody body = rich_damped_body();
  REQUIRE(std::abs(body.integrals().S_o) > 0.1);  // the S_o terms must matter
  REQUIRE(body.damped());
  const std::vector<int> act = {3, 0, 2, 1};  // every element type, shuffled
  const ElasticDynamics el(body, act);
  REQUIRE(el.depends_on_theta());  // the inertial force
  const ZeroOrderModel zero(body);
  const int n = body.n(), N = body.dofs();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  ElasticDynamics::Data data = el.create_data();
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd x0(6), u(4), x1(el.nx());
    x0 << U(rng), U(rng), 4.0 * U(rng), U(rng), U(rng), 3.0 * U(rng);
    for (int k = 0; k < 4; ++k) u(k) = 2.0 * U(rng);
    for (int i = 0; i < el.nx(); ++i) x1(i) = 0.3 * U(rng);
    Eigen::VectorXd commands = Eigen::VectorXd::Zero(4);
    for (int k = 0; k < 4; ++k) commands(act[k]) = u(k);
    RigidState s;
    s.pos = x0.head<3>();
    s.vel = x0.tail<3>();
    s.acc = zero.acceleration(x0, commands);
    const FrozenTrajectory nominal(s);
    const FirstOrderModel fo(body, nominal, [&](const Instant&, Eigen::Ref<Eigen::VectorXd> c) { c = commands; }, {});
    FirstOrderModel::Data fd = fo.create_data();
    // x1 in body axes -> inertial [R1, θ1, q, R1', θ1', q'] (R1 itself enters no equation)
    const Eigen::Matrix2d C0 = rot(x0(2));
    const Eigen::Vector2d v1 = x1.segment<2>(n + 1);
    Eigen::VectorXd xi = Eigen::VectorXd::Zero(2 * N);
    xi(0) = U(rng), xi(1) = U(rng);
    xi(2) = x1(0);
    xi.segment(3, n) = x1.segment(1, n);
    xi.segment<2>(N) = C0 * v1;
    xi(N + 2) = x1(n + 3);
    xi.segment(N + 3, n) = x1.tail(n);
    const Eigen::VectorXd xid = fo.rhs(fd, Instant::at(0.0), xi, Eigen::VectorXd(0));
    el.calc(data, x0(2), x0(5), u, x1);
    Eigen::Matrix2d J;
    J << 0, -1, 1, 0;
    Eigen::VectorXd expect(el.nx());
    expect.head(n + 1) = x1.tail(n + 1);
    expect.segment<2>(n + 1) = C0.transpose() * xid.segment<2>(N) - x0(5) * J * v1;  // v1' = C0ᵀR1'' − θ0' J v1
    expect(n + 3) = xid(N + 2);
    expect.tail(n) = xid.tail(n);
    const double scale = 1.0 + expect.cwiseAbs().maxCoeff();
    // two derivations (body axes, inertial with rotations) and code paths: round-off only
    CHECK((data.f - expect).cwiseAbs().maxCoeff() < 1e-11 * scale);
  }
}

TEST_CASE("stiffening integrals enter the q rows as K - w^2 (M - G_c) - a_x H_bar", "[trajopt]") {
  const FlexibleBody body = rich_damped_body();
  const std::vector<int> act = {3, 0, 2, 1};
  std::mt19937 rng(5);
  const ElasticDynamics::Stiffening st = synthetic_stiffening(body.n(), rng);
  const ElasticDynamics plain(body, act), stiff(body, act, st);
  const ZeroOrderModel zero(body);
  const int n = body.n(), N = body.dofs();
  const Eigen::MatrixXd Mb = body.mass_matrix(0.0, Eigen::VectorXd::Zero(n));
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  ElasticDynamics::Data d0 = plain.create_data(), d1 = stiff.create_data();
  for (int trial = 0; trial < 10; ++trial) {
    Eigen::VectorXd x0(6), u(4), x1(plain.nx());
    x0 << U(rng), U(rng), 4.0 * U(rng), U(rng), U(rng), 3.0 * U(rng);
    for (int k = 0; k < 4; ++k) u(k) = 2.0 * U(rng);
    for (int i = 0; i < plain.nx(); ++i) x1(i) = 0.3 * U(rng);
    Eigen::VectorXd commands = Eigen::VectorXd::Zero(4);
    for (int k = 0; k < 4; ++k) commands(act[k]) = u(k);
    const double a_x = (rot(x0(2)).transpose() * zero.acceleration(x0, commands).head<2>())(0);
    const double w = x0(5);
    const Eigen::VectorXd q = x1.segment(1, n);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(N);
    rhs.tail(n) = (-w * w * st.G_c + a_x * st.H_bar) * q;
    const Eigen::VectorXd expect = Mb.ldlt().solve(rhs);
    plain.calc(d0, x0(2), w, u, x1);
    stiff.calc(d1, x0(2), w, u, x1);
    CHECK(((d1.f - d0.f).tail(N) - expect).cwiseAbs().maxCoeff() < 1e-11 * (1.0 + expect.cwiseAbs().maxCoeff()));
  }
}

TEST_CASE("maneuver dynamics with the elastic part: derivatives match central differences", "[trajopt]") {
  const FlexibleBody body = rich_damped_body();
  std::mt19937 rng(9);
  // all element types (θ-dependent inertial force) and body-fixed actuators only
  for (const std::vector<int>& act : {std::vector<int>{3, 0, 2, 1}, std::vector<int>{2, 3}}) {
    const auto el = std::make_shared<const ElasticDynamics>(body, act, synthetic_stiffening(body.n(), rng));
    const ManeuverDynamics dyn(body, act, el);
    CHECK(el->depends_on_theta() == (act.size() == 4));
    const int nx = dyn.nx(), nz = dyn.nz();
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    ManeuverDynamics::Data data = dyn.create_data();
    Eigen::MatrixXd Jmask = Eigen::MatrixXd::Zero(nx, nz), Hmask = Eigen::MatrixXd::Zero(nz, nz);
    for (const auto& rc : dyn.jacobian_pattern()) Jmask(rc.first, rc.second) = 1.0;
    for (const auto& rc : dyn.hessian_pattern()) {
      CHECK(rc.first >= rc.second);
      Hmask(rc.first, rc.second) = Hmask(rc.second, rc.first) = 1.0;
    }
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::VectorXd z(nz), lam(nx);
      for (int i = 0; i < nz; ++i) z(i) = U(rng);
      z(2) *= 4.0;
      z(5) *= 3.0;
      for (int i = 0; i < nx; ++i) lam(i) = U(rng);
      auto x = [&](const Eigen::VectorXd& zz) { return Eigen::VectorXd(zz.head(nx)); };
      auto uu = [&](const Eigen::VectorXd& zz) { return Eigen::VectorXd(zz.tail(dyn.nu())); };
      dyn.calc_diff(data, x(z), uu(z));
      const Eigen::MatrixXd J = data.J;
      CHECK((dyn.eval(x(z), uu(z)) - data.f).cwiseAbs().maxCoeff() == 0.0);  // one code path
      const Eigen::MatrixXd H = dyn.calc_hessian(data, x(z), uu(z), lam);
      const double h = 1e-6;  // truncation ~h² ~1e-12, round-off ~1e-16/h ~1e-10 on entries up to ~1e2
      Eigen::MatrixXd Jfd(nx, nz), Hfd(nz, nz);
      ManeuverDynamics::Data dp = dyn.create_data(), dm = dyn.create_data();
      for (int i = 0; i < nz; ++i) {
        Eigen::VectorXd zp = z, zm = z;
        zp(i) += h;
        zm(i) -= h;
        dyn.calc_diff(dp, x(zp), uu(zp));
        dyn.calc_diff(dm, x(zm), uu(zm));
        Jfd.col(i) = (dp.f - dm.f) / (2 * h);
        Hfd.col(i) = (dp.J.transpose() * lam - dm.J.transpose() * lam) / (2 * h);
      }
      const double jscale = 1.0 + J.cwiseAbs().maxCoeff(), hscale = 1.0 + H.cwiseAbs().maxCoeff();
      INFO("actuators " << act.size() << " J scale " << jscale << " H scale " << hscale);
      CHECK((J - Jfd).cwiseAbs().maxCoeff() < 1e-6 * jscale);  // see h: measured ~1e-9 relative
      CHECK((H - Hfd).cwiseAbs().maxCoeff() < 1e-6 * hscale);
      // nothing outside the declared patterns
      CHECK((Jfd.array() * (1.0 - Jmask.array())).abs().maxCoeff() < 1e-6 * jscale);
      CHECK((Hfd.array() * (1.0 - Hmask.array())).abs().maxCoeff() < 1e-6 * hscale);
      CHECK((J.array() * (1.0 - Jmask.array())).abs().maxCoeff() == 0.0);
      CHECK((H.array() * (1.0 - Hmask.array())).abs().maxCoeff() == 0.0);
    }
  }
}

TEST_CASE("elastic modes at rest: frequencies, modal rows and the vibration energy", "[trajopt]") {
  const FlexibleBody body = rich_damped_body();
  const ElasticDynamics el(body, {3, 2});
  const int n = body.n();
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Eigen::VectorXd q(n), qd(n);
  for (int i = 0; i < n; ++i) q(i) = U(rng), qd(i) = U(rng);
  const Eigen::VectorXd eta = el.modal_rows() * q, eta_d = el.modal_rows() * qd;
  const double modal = 0.5 * (eta_d.squaredNorm() + (el.mode_frequencies().array() * eta.array()).square().sum());
  // FlexibleBody's eq. 6.8 (its own Schur complement) against the sum over modes
  CHECK(modal == Approx(body.vibration_energy(q, qd)).epsilon(1e-10));
  for (int i = 1; i < n; ++i) CHECK(el.mode_frequencies()(i) >= el.mode_frequencies()(i - 1));
  CHECK(el.excited_modes(0.0).size() == static_cast<std::size_t>(n));  // an off-centre thruster excites all
}

TEST_CASE("a modal truncation keeps the first m modes exactly at rest", "[trajopt]") {
  // Undamped (the truncation's modes are those of K and 𝕄_b at rest); at θ0' = 0, u = 0
  // the free motion of x1 is the elastic modes': Jx's eigenvalues are ±i ω_j.
  const FlexibleBody body(Beam(freeflex_test::rich_beam()), 4, freeflex_test::rich_elements());
  const ElasticDynamics full(body, {3, 2});
  const int n = body.n();
  for (int m : {1, 3, n}) {
    const ElasticDynamics el(body, {3, 2}, m);
    REQUIRE(el.n() == m);
    REQUIRE(el.truncated());
    ElasticDynamics::Data d = el.create_data();
    el.calc_diff(d, 0.3, 0.0, Eigen::Vector2d::Zero(), Eigen::VectorXd::Zero(el.nx()));
    Eigen::EigenSolver<Eigen::MatrixXd> es(d.Jx);
    std::vector<double> w;
    for (int i = 0; i < es.eigenvalues().size(); ++i)
      if (es.eigenvalues()(i).imag() > 1e-6) w.push_back(es.eigenvalues()(i).imag());
    std::sort(w.begin(), w.end());
    REQUIRE(w.size() == static_cast<std::size_t>(m));
    for (int j = 0; j < m; ++j) {
      // the full model's generalized eigenproblem against the truncated Jx (~1e-12 measured)
      CHECK(w[static_cast<std::size_t>(j)] == Approx(full.mode_frequencies()(j)).epsilon(1e-9));
      CHECK(el.mode_frequencies()(j) == Approx(full.mode_frequencies()(j)).epsilon(1e-12));  // the same modes
    }
    // tip deflections through the basis: Φ B ξ equals Φ q with q = B ξ
    const Eigen::VectorXd xi = Eigen::VectorXd::LinSpaced(m, 0.1, 0.7);
    const Eigen::VectorXd q = el.basis() * xi;
    CHECK(el.phi_right().dot(xi) == Approx(full.phi_right().dot(q)).epsilon(1e-12));  // rounding only
  }
  CHECK_THROWS_WITH(ElasticDynamics(body, {3, 2}, 0), Catch::Contains("modes = 0"));
  CHECK_THROWS_WITH(ElasticDynamics(body, {3, 2}, n + 1), Catch::Contains("expected 1 .. " + std::to_string(n)));
}
