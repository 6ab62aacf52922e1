// Modal integration variables (docs/theory.md section 8): the change of variables is
// exact (round trip, derivative), so simulations in either variables agree; and it does
// what it is for, fewer steps when the elastic oscillation is nearly free.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <random>

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "sim/modal_variables.hpp"
#include "freeflex/sim/simulate.hpp"
#include "support/bodies.hpp"

using namespace freeflex;

namespace {

TimeProfile pulse(double amplitude) {
  return TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {amplitude, -amplitude});
}

/// The rich beam (S_o != 0, hub, tip mass), its four force elements, damped modes.
FlexibleBody damped_rich_body() {
  return FlexibleBody(Beam(freeflex_test::rich_beam()), 6, freeflex_test::rich_elements(), {0.02, 0.05, 0.0, 0.3});
}
Excitation rich_loads(double eps) {
  return Excitation{{pulse(eps), pulse(0.5 * eps), pulse(-0.4 * eps), pulse(0.3 * eps)}};
}

SimulationOptions run_options(double duration, double rtol, double atol) {
  SimulationOptions o;
  o.duration_s = duration;
  o.output_step_s = 0.01;
  o.integrator.rtol = rtol;
  o.integrator.atol = atol;
  return o;
}

Eigen::VectorXd random_state(std::mt19937& rng, int N, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd x(2 * N);
  for (int i = 0; i < 2 * N; ++i) x(i) = scale * u(rng);
  x(2) *= 3.0;      // large angles
  x(N + 2) *= 5.0;  // and rates
  return x;
}

/// Checks, at random states and times, that y -> x -> y is the identity and that y' from
/// the modal right-hand side is the derivative of the physical motion: the central
/// difference of x(t) = to_physical(t, y + (t - t1) y') equals f(x) to O(h²).
void check_exact_change(ModalVariables& mv, const ModalVariables::PhysicalRhs& f, int N, double t_s, double t1,
                        double piece_mid) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::VectorXd x0 = random_state(rng, N, 0.05);
    Eigen::VectorXd y(2 * N), x(2 * N), back(2 * N);
    REQUIRE(mv.enter_piece({t_s, piece_mid}, x0, y));
    mv.to_physical({t_s, piece_mid}, y, back);
    INFO("trial " << trial);
    CHECK((back - x0).cwiseAbs().maxCoeff() < 1e-13 * (1.0 + x0.cwiseAbs().maxCoeff()));  // round-off of Φ, Φ⁻¹

    // Later in the piece, at a state reached from y.
    Eigen::VectorXd yd(2 * N), xd(2 * N), xp(2 * N), xm(2 * N);
    REQUIRE(mv.rhs({t1, piece_mid}, y, yd));
    mv.to_physical({t1, piece_mid}, y, x);
    REQUIRE(f({t1, piece_mid}, x, xd));
    auto derivative_error = [&](double h) {
      const Eigen::VectorXd yp = y + h * yd, ym = y - h * yd;
      mv.to_physical({t1 + h, piece_mid}, yp, xp);
      mv.to_physical({t1 - h, piece_mid}, ym, xm);
      return ((xp - xm) / (2.0 * h) - xd).cwiseAbs().maxCoeff() / (1.0 + xd.cwiseAbs().maxCoeff());
    };
    const double e1 = derivative_error(1e-5), e2 = derivative_error(1e-6);
    INFO("relative error of dx/dt: " << e1 << " at h = 1e-5, " << e2 << " at h = 1e-6");
    // Central differences: the error is the O(h²) truncation (the highest modes turn by
    // ω h ~ 0.01 rad at h = 1e-5), so it falls a hundredfold with h; a wrong term would not.
    CHECK(e2 < 1e-7);
    CHECK(e2 < 0.03 * e1);
  }
}

}  // namespace

TEST_CASE("modal variables: exact change for the full model (S_o, hub, tip mass, damping)", "[sim]") {
  const FlexibleBody body = damped_rich_body();
  const FullModel model(body);
  const Excitation ex = rich_loads(1.0);
  auto data = std::make_shared<FullModel::Data>(model.create_data());
  auto u = std::make_shared<Eigen::VectorXd>(body.elements().size());
  const ModalVariables::PhysicalRhs f = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                                            Eigen::Ref<Eigen::VectorXd> xd) {
    *u = ex.commands(at);
    if (!model.rhs(*data, x, *u)) return false;
    xd = data->x_dot;
    return true;
  };
  ModalVariables mv(body, f);
  // The modes: Φᵀ M_c Φ = I is what makes Φ⁻¹ = Φᵀ M_c; frequencies ascending and positive.
  CHECK(mv.natural_frequencies().minCoeff() > 0.0);
  check_exact_change(mv, f, body.dofs(), 0.5, 0.73, 0.75);
}

TEST_CASE("modal variables: exact change for the first-order model about a rotating trajectory", "[sim]") {
  const FlexibleBody body = damped_rich_body();
  const Excitation ex = rich_loads(1.0);
  const PerturbationResult pr = simulate_perturbation(body, ex, run_options(1.5, 1e-8, 1e-10));
  REQUIRE(pr.total.ok());
  REQUIRE(std::abs(pr.nominal->at(Instant::at(0.7)).vel(2)) > 0.1);  // the frame turns
  const FirstOrderModel first(
      body, *pr.nominal, [&ex](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) { c = ex.commands(at); }, {});
  const Eigen::VectorXd none(0);
  FirstOrderModel::Data data = first.create_data();
  const ModalVariables::PhysicalRhs f = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                                            Eigen::Ref<Eigen::VectorXd> xd) {
    xd = first.rhs(data, at, x, none);
    return xd.allFinite();
  };
  ModalVariables mv(body, f, pr.nominal);
  check_exact_change(mv, f, body.dofs(), 0.5, 0.73, 0.75);
}

TEST_CASE("modal and physical variables give the same simulations", "[sim]") {
  const FlexibleBody body = damped_rich_body();
  const Excitation ex = rich_loads(0.3);
  const SimulationOptions opt = run_options(2.0, 1e-10, 1e-13);
  auto run = [&](SimulationOptions::Variables v) {
    SimulationOptions o = opt;
    o.full_variables = o.first_order_variables = v;
    return std::make_pair(simulate_full(body, ex, o), simulate_perturbation(body, ex, o));
  };
  const auto [full_m, pert_m] = run(SimulationOptions::Variables::Modal);
  const auto [full_p, pert_p] = run(SimulationOptions::Variables::Physical);
  REQUIRE(full_m.ok());
  REQUIRE(full_p.ok());
  REQUIRE(pert_m.total.ok());
  REQUIRE(pert_p.total.ok());
  const double scale = full_p.z.cwiseAbs().maxCoeff();
  const double d_full = (full_m.z - full_p.z).cwiseAbs().maxCoeff() / scale;
  const double d_rate = (full_m.z_dot - full_p.z_dot).cwiseAbs().maxCoeff() / full_p.z_dot.cwiseAbs().maxCoeff();
  const double d_pert = (pert_m.total.z - pert_p.total.z).cwiseAbs().maxCoeff() / scale;
  INFO("relative differences: full " << d_full << ", full rates " << d_rate << ", perturbation " << d_pert);
  // both are integration errors at rtol 1e-10, amplified over 2 s of coupled motion
  CHECK(d_full < 1e-7);
  CHECK(d_rate < 1e-7);
  CHECK(d_pert < 1e-7);
}

TEST_CASE("modal variables take far fewer steps where the oscillation is free", "[sim][paper]") {
  // The paper's force pulse: no rotation, so the full model is linear in this motion and
  // the modal amplitudes are constant once the loads end. The first-order model about
  // the paper's moment pulse is linear too.
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  const SimulationOptions o = run_options(3.0, 1e-8, 1e-10);
  const Excitation ex{{pulse(1.0)}};
  auto steps = [&](ForceElement::Type type, bool full, SimulationOptions::Variables v) {
    const FlexibleBody body(beam, 6, {{"load", type, 0.5, {0.0, 1.0}, false}});
    SimulationOptions oo = o;
    oo.full_variables = oo.first_order_variables = v;
    if (full) return simulate_full(body, ex, oo).steps;
    return simulate_perturbation(body, ex, oo).total.steps;
  };
  using V = SimulationOptions::Variables;
  const long force_p = steps(ForceElement::Type::Force, true, V::Physical);
  const long force_m = steps(ForceElement::Type::Force, true, V::Modal);
  const long moment_p = steps(ForceElement::Type::Torque, false, V::Physical);
  const long moment_m = steps(ForceElement::Type::Torque, false, V::Modal);
  INFO("force, full model: " << force_p << " steps physical, " << force_m << " modal");
  INFO("moment, perturbation: " << moment_p << " steps physical, " << moment_m << " modal");
  CHECK(force_m * 10 < force_p);   // measured ~100 times fewer
  CHECK(moment_m * 2 < moment_p);  // measured ~4 times fewer
}
