// Bang-bang switch times that leave the first k excited elastic modes at rest after a
// rest-to-rest rotation of the paper beam (NOA 6) by Δθ = 3 rad with |τ| <= 1 N m.
#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <iostream>

#include "freeflex/control/switch_time.hpp"

using namespace freeflex;
using Catch::Matchers::Contains;

namespace {
FlexibleBody torque_beam() {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  return FlexibleBody(beam, 6, {{"tau", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false}});
}
}  // namespace

TEST_CASE("switch-time design: k = 1, 2 modes at rest in the first-order model", "[control]") {
  const FlexibleBody body = torque_beam();
  const double Tstar = 2.0 * std::sqrt(body.integrals().I_o * 3.0 / 1.0);
  REQUIRE(Tstar == Approx(1.0).epsilon(1e-12));  // I_o = 1/12 kg m²: T* = 2 sqrt(0.25)

  // The rigid bang-bang (one switch) leaves the first antisymmetric mode ringing.
  const BangBangResidual rigid = bang_bang_residual(body, 0, 1.0, {0.5}, 1.0, 2, 1e-11, 1e-14);
  REQUIRE(rigid.ok());
  const double rigid_ratio = rigid.energy_J.sum() / rigid.rigid_kinetic_peak_J;
  std::cout << "[control] rigid bang-bang T* = " << Tstar << " s: residual of the first 2 excited modes "
            << rigid_ratio << " of the rigid kinetic peak " << rigid.rigid_kinetic_peak_J << " J\n";
  CHECK(rigid_ratio > 1e-4);  // so that the designs below have something to remove

  for (int k : {1, 2}) {
    // the torque (element 0) turns the beam by 3 rad with |τ| <= 1 N m
    const SwitchTimeResult r = design_switch_times(body, 0, 3.0, 1.0, k);
    INFO(r.message);
    REQUIRE(r.ok());
    std::cout << "[control] k = " << k << ": T = " << r.duration_s << " s (T* = " << r.rigid_duration_s
              << " s, closed form " << r.closed_form_duration_s << " s with first-order residual "
              << r.closed_form_residual_ratio << "), residual ratio " << r.residual_ratio << ", modes "
              << r.mode_frequencies_rad_s.transpose() << " rad/s, switches";
    for (double s : r.switch_times) std::cout << " " << s;
    std::cout << "; " << r.simulations << " simulations, " << r.wall_time_s << " s\n";
    CHECK(static_cast<int>(r.switch_times.size()) == 2 * k + 1);
    CHECK(r.duration_s > r.rigid_duration_s);
    CHECK(r.residual_ratio < 1e-9);  // the brief's acceptance
    CHECK(r.final_angle_rad == Approx(3.0).epsilon(1e-9));  // rigid rest-to-rest, scaled constraint 1e-7 met to ~1e-12
    CHECK(std::abs(r.final_rate_rad_s) < 1e-12);  // the rest constraint, solved to round-off (measured 9e-16)
    // An independent run at tighter tolerance agrees.
    const BangBangResidual check = bang_bang_residual(body, 0, 1.0, r.switch_times, r.duration_s, k, 1e-12, 1e-15);
    REQUIRE(check.ok());
    const double ratio = check.energy_J.sum() / check.rigid_kinetic_peak_J;
    INFO("re-simulated ratio " << ratio);
    CHECK(ratio < 1e-9);  // the brief's acceptance, on the independent run
    // The closed form ignores θ0'² softening: its design leaves visible ringing in the
    // first-order model (measured 1.5e-2 at k = 1, 1.6e-2 at k = 2).
    CHECK(r.closed_form_residual_ratio > 1e-4);
    // The shortest rotation is near-rigid: T within 0.1% of T* (measured 1.00079 s and
    // 1.00086 s; the longer local designs the search once kept were 1.0378 s and 1.2386 s).
    CHECK(r.duration_s < 1.001 * r.rigid_duration_s);
    // and the work stayed within the bound fixed before the design started
    const SwitchTimeWork bound = switch_time_work(k, SwitchTimeOptions{});
    CHECK(r.closed_form_evaluations <= bound.closed_form_evaluations);
    CHECK(r.simulations <= bound.simulations);
  }
}

TEST_CASE("switch-time design: the work is bounded before any work and a spent budget is a failure with its reason",
          "[control]") {
  const FlexibleBody body = torque_beam();
  SwitchTimeOptions o;
  // the bound of the header: (starts + 30 k²)(max_evaluations + 1), refine_roots ·
  // simulations_per_unknown · (2k + 2) + 2 simulations, steps by max_total_steps
  o.max_steps_per_simulation = 1000;
  SwitchTimeWork w = switch_time_work(2, o);
  CHECK(w.closed_form_evaluations == (24 + 120) * 201);
  CHECK(w.simulations == 4 * 25 * 6 + 2);
  CHECK(w.steps == w.simulations * 1000);  // no total: each simulation's limit
  o.max_total_steps = 5000;
  CHECK(switch_time_work(2, o).steps == 5000);
  CHECK(switch_time_work(0, o).simulations == 1);  // k = 0: the rigid answer, checked once
  CHECK_THROWS_WITH(switch_time_work(5, o), Contains("modes = 5"));
  o.refine_roots = 0;
  CHECK_THROWS_WITH(switch_time_work(1, o), Contains("refine_roots = 0"));

  // A step budget far below one simulation's need (about 10 000 steps here) ends the
  // design at once, naming the setting.
  SwitchTimeOptions tight;
  tight.max_total_steps = 2000;
  const SwitchTimeResult spent = design_switch_times(body, 0, 3.0, 1.0, 1, tight);
  INFO(spent.message);
  CHECK(!spent.ok());
  CHECK_THAT(spent.message, Contains("SwitchTimeOptions::max_total_steps"));
  CHECK(spent.steps <= 2000);
  // Too few simulations per root: each carried root is given up, with that reason.
  SwitchTimeOptions few;
  few.simulations_per_unknown = 2;  // 8 simulations per root for k = 1: one Jacobian and a trial
  const SwitchTimeResult starved = design_switch_times(body, 0, 3.0, 1.0, 1, few);
  INFO(starved.message);
  CHECK(!starved.ok());
  CHECK_THAT(starved.message, Contains("simulations_per_unknown"));
  CHECK(starved.simulations <= switch_time_work(1, few).simulations);
}

TEST_CASE("ZV and ZVD shapers cancel a single mode", "[control]") {
  const double w = 61.7, zeta = 0.02, wd = w * std::sqrt(1.0 - zeta * zeta);
  for (const InputShaper& s : {zv_shaper(w, zeta), zvd_shaper(w, zeta)}) {
    double sum = 0.0;
    std::complex<double> z = 0.0;
    for (std::size_t i = 0; i < s.times.size(); ++i) {
      sum += s.amplitudes[i];
      z += s.amplitudes[i] * std::exp(zeta * w * s.times[i]) * std::polar(1.0, wd * s.times[i]);
    }
    CHECK(sum == Approx(1.0).epsilon(1e-15));  // amplitudes sum to one: a few roundings
    CHECK(std::abs(z) < 1e-14);  // residual vibration of the impulse sequence, exact in closed form
  }
  CHECK(zv_shaper(w).times[1] == Approx(M_PI / w).epsilon(1e-15));  // half the damped period: one rounding
}

TEST_CASE("switch-time design: SLSQP refinement reaches Newton's design (k = 1)", "[control][slow]") {
  const FlexibleBody body = torque_beam();
  SwitchTimeOptions o;  // the defaults' problem: 3 rad with |τ| <= 1 N m by element 0
  const SwitchTimeResult newton = design_switch_times(body, 0, 3.0, 1.0, 1, o);
  o.refine = SwitchTimeOptions::Refine::Slsqp;
  o.max_evaluations = 200;          // SLSQP converges slowly from the closed-form root (measured ~150)
  o.simulations_per_unknown = 200;  // 800 per root (measured 731 used)
  const SwitchTimeResult slsqp = design_switch_times(body, 0, 3.0, 1.0, 1, o);
  REQUIRE(newton.ok());
  INFO(slsqp.message);
  REQUIRE(slsqp.ok());
  std::cout << "[control] k = 1 by SLSQP: T = " << slsqp.duration_s << " s, residual ratio " << slsqp.residual_ratio
            << ", " << slsqp.simulations << " simulations\n";
  CHECK(slsqp.residual_ratio < 1e-9);  // the brief's acceptance
  CHECK(slsqp.duration_s == Approx(newton.duration_s).epsilon(1e-7));  // one root, both to constraint tolerance
  // the same root; SLSQP stops at its optimality tolerance, which leaves single switch times
  // freer than their sum T (a flat direction of the residual near its zero)
  for (int i = 0; i < 3; ++i) CHECK(slsqp.switch_times[i] == Approx(newton.switch_times[i]).epsilon(1e-6));
}
