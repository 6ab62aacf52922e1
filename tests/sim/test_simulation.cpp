// Simulations: conservation laws of the full model, the paper's force example in closed
// form, and second-order agreement of the perturbation solution with the full model.
#include <catch2/catch.hpp>

#include <cmath>

#include "freeflex/sim/simulate.hpp"
#include "support/bodies.hpp"

using namespace freeflex;

namespace {

TimeProfile pulse(double amplitude) {
  return TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {amplitude, -amplitude});
}

/// The paper's beam with one load at the centre.
FlexibleBody paper_body(ForceElement::Type type, int noa = 6) {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  return FlexibleBody(beam, noa, {{"load", type, 0.5, {0.0, 1.0}, false}});
}

SimulationOptions tight(double duration) {
  SimulationOptions o;
  o.duration_s = duration;
  o.output_step_s = 0.01;
  o.integrator.rtol = 1e-10;
  o.integrator.atol = 1e-12;
  o.integrator.method = IntegratorOptions::Method::Adams;
  return o;
}

}  // namespace

TEST_CASE("paper force example: plane motion, mass centre, perturbation = full", "[sim][paper]") {
  const FlexibleBody body = paper_body(ForceElement::Type::Force);
  const Excitation ex{{pulse(1.0)}};
  SimulationOptions opt = tight(3.0);
  opt.integrator.atol = 1e-14;  // coordinates that stay at zero are held to ~atol per step
  const SimulationResult full = simulate_full(body, ex, opt);
  const PerturbationResult pert = simulate_perturbation(body, ex, opt);
  REQUIRE(full.ok());
  REQUIRE(pert.total.ok());
  const int n = body.n();
  // theta, Rx and the antisymmetric q (even-numbered) never move: exactly zero forcing
  INFO("max |Rx| " << full.z.col(0).cwiseAbs().maxCoeff() << ", max |theta| " << full.z.col(2).cwiseAbs().maxCoeff());
  CHECK(full.z.col(0).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(full.z.col(2).cwiseAbs().maxCoeff() < 1e-12);
  for (int j = 1; j < n; j += 2) CHECK(full.z.col(3 + j).cwiseAbs().maxCoeff() < 1e-12);
  // Mass centre y = Ry + Φ̄ q / m follows the rigid solution; Ry0(1 s) = 0.25 m.
  const Eigen::RowVectorXd Pb = body.integrals().Phi_bar / body.integrals().m;
  double worst = 0.0;
  for (int i = 0; i < full.t.size(); ++i) {
    const double t = full.t(i);
    const double rigid = t <= 0.5 ? 0.5 * t * t : t <= 1.0 ? 0.25 - 0.5 * (1 - t) * (1 - t) : 0.25;
    worst = std::max(worst, std::abs(full.z(i, 1) + Pb.dot(full.z.row(i).tail(n)) - rigid));
  }
  INFO("max |mass centre - rigid| = " << worst);
  CHECK(worst < 1e-9);  // the bound; integration error at rtol 1e-10 is ~1e-11
  const double diff = (full.z - pert.total.z).cwiseAbs().maxCoeff();
  INFO("max |full - perturbation| = " << diff);
  CHECK(diff < 1e-8);  // the full model is linear in this motion: integration error only
}

TEST_CASE("a load that starts a round-off span after t = 0 acts as one starting at 0", "[sim]") {
  // Both simulations once failed on a piece [0, 1e-300] (CVODE took the stop time for one
  // behind t = 0; the zero-order samples divided by its length squared).
  const FlexibleBody body = paper_body(ForceElement::Type::Force);
  SimulationOptions opt = tight(1.0);
  opt.integrator.rtol = 1e-8;
  opt.integrator.atol = 1e-10;
  auto run = [&](double start) {
    const Excitation ex{{TimeProfile(TimeProfile::Kind::Steps, {start, 0.5, 1.0}, {1.0, -1.0})}};
    return std::make_pair(simulate_full(body, ex, opt), simulate_perturbation(body, ex, opt));
  };
  const auto [full0, pert0] = run(0.0);
  for (double start : {1e-300, 1e-120}) {
    INFO("the load starts at " << start << " s");
    const auto [full, pert] = run(start);
    INFO(full.message << " / " << pert.total.message);
    REQUIRE(full.ok());
    REQUIRE(pert.total.ok());
    // the same pieces and steps: the same numbers, up to the round-off of the first piece's
    // start (measured 0: the breakpoint is merged into t = 0)
    CHECK((full.z - full0.z).cwiseAbs().maxCoeff() < 1e-14);
    CHECK((pert.total.z - pert0.total.z).cwiseAbs().maxCoeff() < 1e-14);
  }
}

TEST_CASE("a large load over a short first piece still gives its impulse", "[sim]") {
  // 1e12 N for 8e-16 s at the centre: an impulse of 8e-4 N s, which the full model must
  // keep (a rule that merged pieces short relative to the whole run once dropped it).
  const FlexibleBody body = paper_body(ForceElement::Type::Force);
  SimulationOptions opt = tight(1.0);
  opt.integrator.rtol = 1e-8;
  opt.integrator.atol = 1e-10;
  const double width = 8e-16;
  const Excitation ex{{TimeProfile(TimeProfile::Kind::Steps, {0.0, width, 1.0}, {1e12, 0.0})}};
  const SimulationResult full = simulate_full(body, ex, opt);
  INFO(full.message);
  REQUIRE(full.ok());
  const FullModel model(body);
  const int N = body.dofs(), last = static_cast<int>(full.t.size()) - 1;
  Eigen::VectorXd x(2 * N);
  x << full.z.row(last).transpose(), full.z_dot.row(last).transpose();
  // momentum after the loads end = the impulse 1e12 * 8e-16 along y, to integration error
  // (rtol 1e-8) on the impulse's own scale
  const Eigen::Vector2d P = model.linear_momentum(x);
  CHECK(P(1) == Approx(1e12 * width).epsilon(1e-6));
  CHECK(std::abs(P(0)) < 1e-6 * 1e12 * width);
}

TEST_CASE("paper moment example: only theta and antisymmetric q, perturbation differs", "[sim][paper]") {
  const FlexibleBody body = paper_body(ForceElement::Type::Torque);
  const Excitation ex{{pulse(1.0)}};
  const SimulationOptions opt = tight(3.0);
  const SimulationResult full = simulate_full(body, ex, opt);
  const PerturbationResult pert = simulate_perturbation(body, ex, opt);
  REQUIRE(full.ok());
  REQUIRE(pert.total.ok());
  // the bound; symmetry keeps them at round-off (measured 1e-16)
  CHECK(full.z.leftCols(2).cwiseAbs().maxCoeff() < 1e-12);
  for (int j = 0; j < body.n(); j += 2) CHECK(full.z.col(3 + j).cwiseAbs().maxCoeff() < 1e-12);
  // zero-order: theta0'' = 12 rad/s^2, theta0'(0.5) = 6 rad/s, theta0(1) = 3 rad
  const int i1 = 100;  // t = 1.0 at output step 0.01
  REQUIRE(pert.zero_order.t(i1) == Approx(1.0).epsilon(1e-14));  // output grid: a few ulp
  // integration error at rtol 1e-10 on a piecewise quadratic (measured 6e-13 relative)
  CHECK(pert.zero_order.z(i1, 2) == Approx(3.0).epsilon(1e-9));
  // a very flexible beam at 6 rad/s: the two solutions differ visibly (docs/theory.md 9)
  CHECK((full.z - pert.total.z).col(2).cwiseAbs().maxCoeff() > 1e-2);
}

namespace {
/// The rich beam with an inertial force, a follower thruster and a torque, with the
/// paper's pulse timing (tests/support/bodies.hpp).
FlexibleBody rich_body(bool stiffening = false) {
  auto el = freeflex_test::rich_elements();
  el.erase(el.begin() + 2);  // no body thruster: three loads
  return FlexibleBody(Beam(freeflex_test::rich_beam()), 6, el, {}, stiffening);
}
Excitation rich_loads(double eps) { return Excitation{{pulse(eps), pulse(0.5 * eps), pulse(0.3 * eps)}}; }

/// max |full - perturbation| over the run for loads scaled by eps.
double perturbation_error(const FlexibleBody& body, const Excitation& ex) {
  SimulationOptions opt = tight(3.0);
  opt.integrator.atol = 1e-15;  // resolve differences down to ~1e-8 at eps = 0.01
  const SimulationResult full = simulate_full(body, ex, opt);
  const PerturbationResult pert = simulate_perturbation(body, ex, opt);
  REQUIRE(full.ok());
  REQUIRE(pert.total.ok());
  return (full.z - pert.total.z).cwiseAbs().maxCoeff();
}
}  // namespace

TEST_CASE("perturbation error falls as the square of the load", "[sim]") {
  const bool stiffening = GENERATE(false, true);  // issue 14, acceptance 3: also with stiffening
  INFO("geometric stiffening " << stiffening);
  const FlexibleBody body = rich_body(stiffening);
  double prev = 0.0;
  for (double eps : {1.0, 0.1, 0.01}) {
    const double d = perturbation_error(body, rich_loads(eps));
    INFO("eps " << eps << ": max |full - perturbation| = " << d << ", ratio to previous " << prev / d);
    if (prev > 0.0) CHECK(prev / d >= 50.0);  // the bound (second order gives ~100)
    prev = d;
  }
}

TEST_CASE("paper moment example: second order once out of the large-rotation regime", "[sim][paper]") {
  // At eps = 1 the rate reaches 6 rad/s and theta differs by 0.28 rad: not asymptotic,
  // the first decade only gains ~42 (docs/theory.md section 9). From eps = 0.1 on the
  // error falls at least as eps^2.
  const FlexibleBody body = paper_body(ForceElement::Type::Torque);
  const double d1 = perturbation_error(body, Excitation{{pulse(0.1)}});
  const double d2 = perturbation_error(body, Excitation{{pulse(0.01)}});
  INFO("eps 0.1: " << d1 << ", eps 0.01: " << d2);
  CHECK(d1 / d2 >= 100.0);  // second order or better
}

TEST_CASE("full model conserves energy and momenta after the loads end", "[sim]") {
  const bool stiffening = GENERATE(false, true);  // issue 14, acceptance 4: also the stiffened model (eq. 14.8)
  // and both integrated in rest-mode coordinates, checked in physical ones
  const bool rest_modes = GENERATE(false, true);
  INFO("geometric stiffening " << stiffening << ", rest-mode coordinates " << rest_modes);
  const FlexibleBody body = rich_body(stiffening);
  const Excitation ex = rich_loads(1.0);
  SimulationOptions opt = tight(10.0);
  if (rest_modes) opt.full_variables = SimulationOptions::Variables::RestModes;
  // atol 1e-14 for both (rtol stays the 1e-10). Stiffened: the momenta drift 1.1e-8 /
  // 1.6e-8 at atol 1e-12 (integration error: 7e-9 / 1.1e-8 at 1e-13, 1.8e-9 / 2.5e-9 at 1e-14).
  // Unstiffened, on the one-sided basis of the off-centre o: energy balance 2.6e-8 of E at
  // atol 1e-12, 2.8e-9 at 1e-14 (integration error, falling with atol).
  opt.integrator.atol = 1e-14;
  opt.energy_balance = true;
  const SimulationResult r = simulate_full(body, ex, opt);
  REQUIRE(r.ok());
  const FullModel model(body);
  const int N = body.dofs();
  auto state = [&](int i) {
    Eigen::VectorXd x(2 * N);
    x << r.z.row(i).transpose(), r.z_dot.row(i).transpose();
    return x;
  };
  const int i_off = 100;  // t = 1 s
  REQUIRE(r.t(i_off) == Approx(1.0).epsilon(1e-14));  // output grid: a few ulp
  const double E0 = model.energy(state(i_off)), H0 = model.angular_momentum(state(i_off));
  const Eigen::Vector2d P0 = model.linear_momentum(state(i_off));
  double dE = 0, dP = 0, dH = 0;
  for (int i = i_off; i < r.t.size(); ++i) {
    dE = std::max(dE, std::abs(model.energy(state(i)) - E0) / std::abs(E0));
    dP = std::max(dP, (model.linear_momentum(state(i)) - P0).norm() / P0.norm());
    dH = std::max(dH, std::abs(model.angular_momentum(state(i)) - H0) / std::abs(H0));
  }
  INFO("relative drift over 9 s: energy " << dE << ", linear momentum " << dP << ", angular momentum " << dH);
  // the energy balance of the run (work of the loads integrated along the solution)
  double balance = 0.0;
  for (int i = 0; i < r.t.size(); ++i)
    balance = std::max(balance, std::abs(model.energy(state(i)) - model.energy(state(0)) - r.work_J(i)));
  INFO("energy balance: max |E - E(0) - W| = " << balance << " J of " << E0 << " J");
  CHECK(balance < 1e-8 * std::abs(E0));  // quadrature on the states' steps at rtol 1e-10
  CHECK(dE < 1e-8);  // the bound at rtol 1e-10
  CHECK(dP < 1e-8);
  CHECK(dH < 1e-8);
}

TEST_CASE("the global error estimate is within a factor of 10 of the error against a tight reference", "[sim]") {
  // The paper's moment example to 1 s (the large-rotation regime, where the full model's
  // error grows fastest), NOA 6; reference: the same model at rtol 1e-13 in physical variables.
  const FlexibleBody body = paper_body(ForceElement::Type::Torque);
  const Excitation ex{{pulse(1.0)}};
  SimulationOptions ref = tight(1.0);
  ref.integrator.rtol = 1e-13;
  ref.integrator.atol = 1e-15;
  const SimulationResult exact = simulate_full(body, ex, ref);
  REQUIRE(exact.ok());
  const PerturbationResult exact_p = simulate_perturbation(body, ex, ref);
  REQUIRE(exact_p.total.ok());
  for (double rtol : {1e-6, 1e-8}) {
    for (auto v : {SimulationOptions::Variables::Physical, SimulationOptions::Variables::Modal}) {
      SimulationOptions o = tight(1.0);
      o.integrator.rtol = rtol;
      o.integrator.atol = rtol * 1e-2;
      o.full_variables = o.first_order_variables = v;
      const SimulationOptions o2 = error_reference_options(o);
      CHECK(o2.integrator.rtol == rtol / kErrorEstimateFactor);  // the same expression as error_reference_options
      for (bool full : {true, false}) {
        const SimulationResult run = full ? simulate_full(body, ex, o) : simulate_perturbation(body, ex, o).total;
        const SimulationResult again =
            full ? simulate_full(body, ex, o2) : simulate_perturbation(body, ex, o2).total;
        const GlobalErrorEstimate e = compare_runs(run, again, o2);
        REQUIRE(e.available);
        const Eigen::MatrixXd dz = (run.z - (full ? exact.z : exact_p.total.z)).cwiseAbs();
        const double err_theta = dz.col(2).maxCoeff(), err_q = dz.rightCols(body.n()).maxCoeff();
        INFO("rtol " << rtol << (full ? " full" : " perturbation") << (v == SimulationOptions::Variables::Modal ? " modal" : " physical")
                     << ": theta error " << err_theta << " estimate " << e.theta_rad << "; q error " << err_q
                     << " estimate " << e.q);
        // acceptance 2 of issue 19: the estimate within a factor of 10 of the measured error
        CHECK(e.theta_rad <= 10.0 * err_theta);
        CHECK(e.theta_rad >= 0.1 * err_theta);
        CHECK(e.q <= 10.0 * err_q);
        CHECK(e.q >= 0.1 * err_q);
      }
    }
  }
}

TEST_CASE("compare_runs reports a failed or mismatched second run as unavailable", "[sim]") {
  SimulationResult a, b;
  a.status = IntegrationStatus::Completed;
  a.t = Eigen::VectorXd::LinSpaced(3, 0.0, 1.0);
  a.z = a.z_dot = Eigen::MatrixXd::Zero(3, 5);
  b.status = IntegrationStatus::Failed;
  b.message = "too much work at t = 0.5";
  const SimulationOptions o = error_reference_options(SimulationOptions{});
  GlobalErrorEstimate e = compare_runs(a, b, o);
  CHECK_FALSE(e.available);
  CHECK(e.message.find("too much work") != std::string::npos);
  b = a;
  b.t(1) = 0.25;
  e = compare_runs(a, b, o);
  CHECK_FALSE(e.available);
  b = a;
  b.z(1, 2) = 1e-3;
  b.z(2, 4) = -2e-4;
  e = compare_runs(a, b, o);
  REQUIRE(e.available);
  CHECK(e.theta_rad == 1e-3);
  CHECK(e.q == 2e-4);
  CHECK(e.R_m == 0.0);
  CHECK(e.worst_time_s == 0.5);
  b.z_dot(2, 0) = std::nan("");  // never an estimate from a non-finite difference
  e = compare_runs(a, b, o);
  CHECK_FALSE(e.available);
  CHECK(e.message.find("not finite") != std::string::npos);
}

TEST_CASE("rest-mode coordinates: the full model's motion, its range check and the first-order model refused", "[sim]") {
  // The same equations as physical coordinates: at rtol 1e-11 the two runs of the paper's
  // moment example (damped, NOA 8, to 1 s) differ by their integration errors only.
  const FlexibleBody body = freeflex_test::moment_body(8, {0.02, 0.01});
  const Excitation ex = freeflex_test::moment_loads();
  SimulationOptions o = tight(1.0);
  o.integrator.rtol = 1e-11;
  o.integrator.atol = 1e-13;
  o.integrator.method = IntegratorOptions::Method::Dop853;
  o.energy_balance = true;
  const SimulationResult physical = simulate_full(body, ex, o);
  o.full_variables = SimulationOptions::Variables::RestModes;
  const SimulationResult rest = simulate_full(body, ex, o);
  REQUIRE(physical.ok());
  REQUIRE(rest.ok());
  REQUIRE(rest.work_J.size() == rest.t.size());
  const double dz = (physical.z - rest.z).cwiseAbs().maxCoeff(), dzd = (physical.z_dot - rest.z_dot).cwiseAbs().maxCoeff();
  const double dw = (physical.work_J - rest.work_J).cwiseAbs().maxCoeff();
  INFO("largest differences: z " << dz << ", z' " << dzd << ", work " << dw);
  // Against Adams at rtol 1e-13 each run is off by 2e-10 in z and 6e-8 in z' (seen for both
  // coordinates at rtol 1e-10 to 1e-12: the reference's own floor); 10 times that. A state
  // or output not mapped between the coordinates is off by the size of q (1e-2).
  CHECK(dz < 2e-9);
  CHECK(dzd < 6e-7);
  CHECK(dw < 1e-9);  // the work reaches 0.3 J; seen 1e-11
  CHECK(rest.z(rest.t.size() - 1, 2) > 2.5);  // the maneuver happened (3 rad rigid, the tangent at o tilted by 0.15)

  // the deflection check sees q, not η: with a limit at half the run's largest deflection
  // both coordinates stop at the same output time with the same figure in the message
  const Eigen::MatrixXd P = deflection_sampler(body);
  double peak = 0.0;
  for (Eigen::Index i = 0; i < physical.t.size(); ++i)
    peak = std::max(peak, (P * physical.z.row(i).tail(body.n()).transpose()).cwiseAbs().maxCoeff());
  SimulationOptions bent = o;
  bent.max_deflection_ratio = 0.5 * peak / 1.0;  // the beam is 1 m long
  bent.full_variables = SimulationOptions::Variables::Physical;
  const SimulationResult stopped_physical = simulate_full(body, ex, bent);
  bent.full_variables = SimulationOptions::Variables::RestModes;
  const SimulationResult stopped = simulate_full(body, ex, bent);
  CHECK(stopped_physical.status == IntegrationStatus::OutOfRange);
  CHECK(stopped.status == IntegrationStatus::OutOfRange);
  CHECK(stopped.t.size() == stopped_physical.t.size());
  CHECK(stopped.message == stopped_physical.message);  // "the elastic deflection reached ... m" to 4 digits

  // a given initial state is mapped in and the motion from it is the physical one
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(2 * body.dofs());
  x0(2) = 0.3;
  x0(body.dofs() + 2) = 1.5;  // spinning
  for (int i = 0; i < body.n(); ++i) {
    x0(3 + i) = 0.01 / (i + 1);
    x0(body.dofs() + 3 + i) = 0.05 * (i % 2 ? 1 : -1);
  }
  o.full_variables = SimulationOptions::Variables::Physical;
  const SimulationResult from_physical = simulate_full(body, ex, o, x0);
  o.full_variables = SimulationOptions::Variables::RestModes;
  const SimulationResult from_rest = simulate_full(body, ex, o, x0);
  REQUIRE(from_physical.ok());
  REQUIRE(from_rest.ok());
  CHECK((from_rest.z.row(0).transpose() - x0.head(body.dofs())).cwiseAbs().maxCoeff() < 1e-15);
  CHECK((from_rest.z - from_physical.z).cwiseAbs().maxCoeff() < 2e-9);  // as above: integration error

  // not for the first-order model
  SimulationOptions first = tight(1.0);
  first.first_order_variables = SimulationOptions::Variables::RestModes;
  CHECK_THROWS_WITH(validate(first), Catch::Contains("first_order_variables"));
}

TEST_CASE("rest-mode coordinates: the tolerances mean the same whatever the beam's mass", "[sim]") {
  // Mass and stiffness scaled together leave the motion (and the physical run's steps)
  // unchanged; the rest-mode amplitudes are scaled to the size of q, so their steps must not
  // move either. Here: physical 2 172 and 2 170 steps at m = 0.01 and 1e4, rest modes 2 111
  // at both; unscaled (M_c-normalized amplitudes grow as √m) 1 972 and 2 201.
  std::vector<long> steps;
  for (double m : {0.01, 1e4}) {
    const FlexibleBody body(Beam(BeamProperties::uniform(1.0, m, m)), 12,
                            {{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}}, {0.02}, false);
    const Excitation ex{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {m, -m})}};
    SimulationOptions o = tight(1.0);
    o.integrator.rtol = 1e-7;
    o.integrator.atol = 1e-9;
    o.integrator.method = IntegratorOptions::Method::Dop853;
    const SimulationResult physical = simulate_full(body, ex, o);
    o.full_variables = SimulationOptions::Variables::RestModes;
    const SimulationResult rest = simulate_full(body, ex, o);
    REQUIRE(physical.ok());
    REQUIRE(rest.ok());
    INFO("m = " << m << ": steps " << physical.steps << " physical, " << rest.steps << " rest modes");
    // the same equations, so within a few per cent (2.8% here; 0.6% at NOA 20, rtol 1e-6)
    CHECK(std::abs(rest.steps - physical.steps) < 0.05 * physical.steps);
    steps.push_back(rest.steps);
  }
  // mass and stiffness scaled together: the same run up to round-off (the physical runs
  // differ by 2 of 2 170 steps)
  CHECK(std::abs(steps[0] - steps[1]) <= 0.01 * steps[0]);
}
