// RigidDynamics (trajopt/rigid_dynamics.hpp): values against the zero-order model, and
// its analytic first and second derivatives against central differences.
#include <catch2/catch.hpp>

#include <random>

#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/trajopt/rigid_dynamics.hpp"

using namespace freeflex;

namespace {

/// o off the mass centre (S_o != 0), a hub and a tip mass; one element of each type,
/// thrusters with and without follow_slope.
FlexibleBody rich_body() {
  BeamProperties p;
  p.segments = {{0.6, 1.2, 2.0}, {0.5, 0.7, 1.1}};
  p.reference_m = 0.3;
  p.hub_mass_kg = 0.3;
  p.hub_rotary_inertia_kgm2 = 0.02;
  p.point_masses = {{1.1, 0.25}};
  std::vector<ForceElement> el;
  el.push_back({"force", ForceElement::Type::Force, 0.9, {0.3, -0.8}, false});
  el.push_back({"follower", ForceElement::Type::Thruster, 1.1, {0.2, 1.0}, true});
  el.push_back({"thruster", ForceElement::Type::Thruster, 0.1, {-0.5, 0.4}, false});
  el.push_back({"torque", ForceElement::Type::Torque, 0.7, {0.0, 0.0}, false});
  return FlexibleBody(Beam(p), 4, el);
}

}  // namespace

TEST_CASE("rigid dynamics reproduces the zero-order model and element forces", "[trajopt]") {
  const FlexibleBody body = rich_body();
  REQUIRE(std::abs(body.integrals().S_o) > 0.1);  // the S_o terms must matter for the test to mean anything
  const std::vector<int> act = {3, 0, 2, 1};  // every type, in a shuffled order
  const RigidDynamics dyn(body, act);
  const ZeroOrderModel zero(body);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(body.n());
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd x(6), u(4);
    x << U(rng), U(rng), 4.0 * U(rng), U(rng), U(rng), 3.0 * U(rng);
    for (int k = 0; k < 4; ++k) u(k) = 2.0 * U(rng);
    Eigen::VectorXd commands = Eigen::VectorXd::Zero(4);
    for (int k = 0; k < 4; ++k) commands(act[k]) = u(k);
    const Eigen::VectorXd xdot = zero.rhs(x, commands);
    // two different solution paths (LDLT of 𝕄_rr vs the Schur-complement closed form)
    CHECK((dyn.eval(x, u) - xdot).cwiseAbs().maxCoeff() < 1e-12 * (1.0 + xdot.cwiseAbs().maxCoeff()));
    for (int k = 0; k < 4; ++k) {
      const Eigen::VectorXd g = body.element_force(act[k], x(2), q0);
      // same trigonometric terms evaluated in another order: round-off only
      CHECK((dyn.actuator_force(k, x(2)) - g.head<3>()).cwiseAbs().maxCoeff() < 1e-14);
    }
  }
}

TEST_CASE("rigid dynamics Jacobian and Hessian contraction match central differences", "[trajopt]") {
  const FlexibleBody body = rich_body();
  const RigidDynamics dyn(body, {0, 1, 2, 3});
  const int nz = dyn.nz();
  REQUIRE(nz == 10);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const double h = 1e-6;  // central differences: truncation ~h^2 f''' ~1e-12, round-off ~eps/h ~1e-10
  for (int trial = 0; trial < 30; ++trial) {
    Eigen::VectorXd z(nz), lam(6);
    z << U(rng), U(rng), 4.0 * U(rng), U(rng), U(rng), 3.0 * U(rng), 2 * U(rng), 2 * U(rng), 2 * U(rng), 2 * U(rng);
    for (int i = 0; i < 6; ++i) lam(i) = U(rng);
    RigidDynamics::Data data = dyn.create_data(), plus = dyn.create_data(), minus = dyn.create_data();
    dyn.calc_diff(data, z.head(6), z.tail(4));
    const Eigen::VectorXd f = data.f;
    const Eigen::MatrixXd J = data.J;
    CHECK((f - dyn.eval(z.head(6), z.tail(4))).cwiseAbs().maxCoeff() == 0.0);
    const Eigen::MatrixXd H = dyn.calc_hessian(data, z.head(6), z.tail(4), lam);
    Eigen::MatrixXd Jfd(6, nz), Hfd(nz, nz);
    for (int c = 0; c < nz; ++c) {
      Eigen::VectorXd zp = z, zm = z;
      zp(c) += h;
      zm(c) -= h;
      dyn.calc_diff(plus, zp.head(6), zp.tail(4));
      dyn.calc_diff(minus, zm.head(6), zm.tail(4));
      const Eigen::MatrixXd &Jp = plus.J, &Jm = minus.J;
      Jfd.col(c) = (plus.f - minus.f) / (2 * h);
      Hfd.col(c) = ((lam.transpose() * Jp) - (lam.transpose() * Jm)).transpose() / (2 * h);
    }
    INFO("trial " << trial);
    CHECK((J - Jfd).cwiseAbs().maxCoeff() < 1e-8);  // see h above, entries O(1..10)
    CHECK((H - Hfd).cwiseAbs().maxCoeff() < 1e-8);  // same differences of the analytic Jacobian
    CHECK((H - H.transpose()).cwiseAbs().maxCoeff() == 0.0);  // the documented contract: every entry written, symmetric

    // Entries outside the declared sparsity patterns are exactly zero.
    Eigen::MatrixXd Jmask = J, Hmask = H;
    for (const auto& rc : dyn.jacobian_pattern()) Jmask(rc.first, rc.second) = 0.0;
    for (const auto& rc : dyn.hessian_pattern()) Hmask(rc.first, rc.second) = Hmask(rc.second, rc.first) = 0.0;
    CHECK(Jmask.cwiseAbs().maxCoeff() == 0.0);
    CHECK(Hmask.cwiseAbs().maxCoeff() == 0.0);
  }
}

TEST_CASE("rigid dynamics rejects bad actuator lists", "[trajopt]") {
  const FlexibleBody body = rich_body();
  using Catch::Matchers::Contains;
  CHECK_THROWS_WITH(RigidDynamics(body, {}), Contains("actuators is empty"));
  CHECK_THROWS_WITH(RigidDynamics(body, {0, 4}), Contains("actuators[1] = 4") && Contains("[0, 3]"));
  CHECK_THROWS_WITH(RigidDynamics(body, {2, 2}), Contains("repeats actuators[0]"));
}
