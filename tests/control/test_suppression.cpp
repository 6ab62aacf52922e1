// The suppression chain in one call (control/suppression.hpp): the same results as its
// steps called one by one, the phases reported in order, bad input refused before any
// work and a horizon shorter than the maneuver reported as a status.
#include <catch2/catch.hpp>

#include <vector>

#include "freeflex/control/suppression.hpp"

using namespace freeflex;
using Catch::Contains;

namespace {

FlexibleBody pulse_body() {
  return FlexibleBody(Beam(BeamProperties::uniform(1.0, 1.0, 1.0)), 4,
                      {{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false},
                       {"tau", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false},
                       {"right", ForceElement::Type::Thruster, 1.0, {0.0, 1.0}, false}});
}

SuppressionProblem pulse_problem(const FlexibleBody& body) {
  SuppressionProblem p;
  p.loads = Excitation{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0}), std::nullopt,
                        std::nullopt}};
  p.actuators = {1, 2};
  p.limits = Eigen::Vector2d(1.0, 2.0);
  p.Q = vibration_weight(body, 1.0, 10.0, 1.0);
  p.R = Eigen::Vector2d(1.0, 0.25).asDiagonal();
  p.horizon_s = p.until_s = 2.0;
  return p;
}

}  // namespace

TEST_CASE("suppress_vibration gives what its steps give one by one", "[control]") {
  const FlexibleBody body = pulse_body();
  const SuppressionProblem p = pulse_problem(body);
  SuppressionOptions o;
  o.simulation.output_step_s = 0.01;
  std::vector<std::pair<SuppressionPhase, bool>> phases;
  o.on_phase = [&phases](SuppressionPhase ph, bool done, double, const SuppressionResult&) {
    phases.emplace_back(ph, done);
  };
  const SuppressionResult r = suppress_vibration(body, p, o);
  REQUIRE(r.ok());
  const std::vector<std::pair<SuppressionPhase, bool>> expected{
      {SuppressionPhase::OpenLoop, false}, {SuppressionPhase::OpenLoop, true}, {SuppressionPhase::Tvlqr, false},
      {SuppressionPhase::Tvlqr, true},     {SuppressionPhase::ClosedLoop, false}, {SuppressionPhase::ClosedLoop, true}};
  CHECK(phases == expected);

  // The same steps by hand: open loop, the first-order model, TV-LQR, closed loop.
  SimulationOptions so = o.simulation;
  so.duration_s = p.until_s;
  const PerturbationResult pert = simulate_perturbation(body, p.loads, so);
  const FirstOrderModel model(body, *pert.nominal, nominal_element_commands(p.loads, p.actuators), p.actuators);
  TvlqrOptions to;
  to.breakpoints = p.loads.breakpoints();
  const TvlqrResult law = solve_tvlqr(model, 0.0, p.horizon_s, p.Q, p.R, to);
  ClosedLoopOptions co;
  co.t_end = p.until_s;
  co.output_step_s = so.output_step_s;
  co.limits = p.limits;
  co.breakpoints = p.loads.breakpoints();
  const ClosedLoopResult full = simulate_closed_loop_full(model, p.loads, {}, law, co);
  REQUIRE(full.ok());
  // one computation, two call paths: equal to the bit
  CHECK(r.open_loop_first_order.total.z == pert.total.z);
  CHECK(r.law.K.back() == law.K.back());
  CHECK(r.law.feedforward == law.feedforward);
  CHECK(r.closed_loop_full.z == full.z);
  CHECK(r.closed_loop_full.commands == full.commands);
}

TEST_CASE("suppress_vibration refuses bad input before any work", "[control]") {
  const FlexibleBody body = pulse_body();
  SuppressionProblem p = pulse_problem(body);
  p.limits = Eigen::Vector3d(1.0, 1.0, 1.0);
  CHECK_THROWS_WITH(suppress_vibration(body, p), Contains("expected one limit per feedback actuator (2), got 3"));
  p = pulse_problem(body);
  p.R(1, 1) = -1.0;
  CHECK_THROWS_WITH(suppress_vibration(body, p), Contains("R must be positive definite"));
  p = pulse_problem(body);
  p.actuators = {1, 7};
  CHECK_THROWS_WITH(suppress_vibration(body, p), Contains("actuator 7 is not an element of the body"));
  p = pulse_problem(body);
  SuppressionOptions o;
  o.tvlqr.grid_step_s = -1.0;
  CHECK_THROWS_WITH(suppress_vibration(body, p, o), Contains("grid_step_s = -1"));
}

TEST_CASE("a maneuver longer than the horizon is a status, not an exception", "[control]") {
  const FlexibleBody body = pulse_body();
  SuppressionProblem p = pulse_problem(body);
  FlownManeuver m;
  m.motion = std::make_shared<SampledRigidTrajectory>(std::vector<SampledRigidTrajectory::Piece>{
      {{0.0, 3.0}, {RigidState{}, RigidState{}}}});  // at rest, 3 s long
  m.actuators = {1};
  m.commands = [](const Instant&, Eigen::Ref<Eigen::VectorXd> u) { u.setZero(); };
  m.duration_s = 3.0;
  p.maneuver = m;
  const SuppressionResult r = suppress_vibration(body, p);
  CHECK(r.status == SuppressionResult::Status::HorizonTooShort);
  CHECK_FALSE(r.ok());
  CHECK_THAT(r.message, Contains("horizon_s = 2 is shorter than the maneuver (3 s)"));
}
