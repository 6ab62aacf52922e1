// Bad input to the control layer throws std::invalid_argument naming what was wrong.
#include <catch2/catch.hpp>

#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/lqr.hpp"
#include "freeflex/control/metrics.hpp"
#include "freeflex/control/switch_time.hpp"
#include "freeflex/control/tvlqr.hpp"

using namespace freeflex;
using Catch::Matchers::Contains;

namespace {

FlexibleBody beam_with_actuators() {
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  return FlexibleBody(beam, 2,
                      {{"tau", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false},
                       {"tip", ForceElement::Type::Thruster, 1.0, {0.0, 1.0}, false}});
}

/// A maneuver that ends at t = 2 s (the rigid state itself does not matter here).
class TwoSecondManeuver : public RigidTrajectory {
 public:
  RigidState at(const Instant&) const override { return {}; }
  double t_begin() const override { return 0.0; }
  double t_end() const override { return 2.0; }
  std::vector<double> breakpoints() const override { return {}; }
};

CommandFunction zero() {
  return [](const Instant&, Eigen::Ref<Eigen::VectorXd> c) { c.setZero(); };
}

}  // namespace

TEST_CASE("CARE rejects Q not PSD and R not PD with the smallest eigenvalue", "[control]") {
  Eigen::MatrixXd A(2, 2), B(2, 1), Q = Eigen::Vector2d(1.0, -0.3).asDiagonal(), R = Eigen::MatrixXd::Ones(1, 1);
  A << 0, 1, 0, 0;
  B << 0, 1;
  CHECK_THROWS_WITH(solve_care(A, B, Q, R), Contains("Q must be positive semidefinite: smallest eigenvalue -0.3"));
  const Eigen::MatrixXd I2 = Eigen::MatrixXd::Identity(2, 2);
  CHECK_THROWS_WITH(solve_care(A, B, I2, Eigen::MatrixXd::Zero(1, 1)),
                    Contains("R must be positive definite: smallest eigenvalue 0"));
  CHECK_THROWS_WITH(solve_care(A, B, Eigen::MatrixXd::Identity(3, 3), R), Contains("Q must be 2 x 2, got 3 x 3"));
  Eigen::MatrixXd Qa = I2;
  Qa(0, 1) = 0.5;
  CHECK_THROWS_WITH(solve_care(A, B, Qa, R), Contains("Q must be symmetric"));
  CHECK_THROWS_AS(solve_care(A, Eigen::MatrixXd::Ones(3, 1), I2, R), std::invalid_argument);
}

TEST_CASE("TV-LQR rejects bad weights, an empty horizon and one shorter than the maneuver", "[control]") {
  const FlexibleBody body = beam_with_actuators();
  const TwoSecondManeuver nominal;
  const FirstOrderModel model(body, nominal, zero(), {0, 1});
  const int nx = model.state_size();
  const Eigen::MatrixXd Q = Eigen::MatrixXd::Identity(nx, nx), R = Eigen::MatrixXd::Identity(2, 2);
  const TvlqrOptions o;

  Eigen::MatrixXd bad_Q = Q;
  bad_Q(4, 4) = -0.3;
  CHECK_THROWS_WITH(solve_tvlqr(model, 0.0, 3.0, bad_Q, R, o),
                    Contains("tvlqr: Q must be positive semidefinite: smallest eigenvalue -0.3"));
  Eigen::MatrixXd bad_R = R;
  bad_R(1, 1) = -2.0;
  CHECK_THROWS_WITH(solve_tvlqr(model, 0.0, 3.0, Q, bad_R, o),
                    Contains("tvlqr: R must be positive definite: smallest eigenvalue -2"));
  TvlqrOptions bad = o;
  bad.Qf = -Eigen::MatrixXd::Identity(nx, nx);
  CHECK_THROWS_WITH(solve_tvlqr(model, 0.0, 3.0, Q, R, bad), Contains("Qf must be positive semidefinite"));
  CHECK_THROWS_WITH(solve_tvlqr(model, 0.0, 3.0, Q, Eigen::MatrixXd::Identity(3, 3), o),
                    Contains("R must be 2 x 2, got 3 x 3"));
  // the maneuver ends at 2 s
  CHECK_THROWS_WITH(solve_tvlqr(model, 0.0, 1.5, Q, R, o),
                    Contains("tf = 1.5 s ends before the nominal maneuver does (2 s)"));
  CHECK_THROWS_WITH(solve_tvlqr(model, 3.0, 3.0, Q, R, o), Contains("tf = 3 must be > t0 = 3"));
  bad = o;
  bad.grid_step_s = 0.0;
  CHECK_THROWS_WITH(solve_tvlqr(model, 0.0, 3.0, Q, R, bad), Contains("grid_step_s"));
}

TEST_CASE("actuators that are not in the model are rejected", "[control]") {
  const FlexibleBody body = beam_with_actuators();
  const TwoSecondManeuver nominal;
  CHECK_THROWS_WITH(FirstOrderModel(body, nominal, zero(), {0, 7}), Contains("input index 7 is not an element"));
  const Excitation loads{{std::nullopt, std::nullopt}};
  CHECK_THROWS_WITH(nominal_element_commands(loads, {0, 5}), Contains("is element 5, not an element"));
  const Excitation load_on_actuator{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 1.0}, {1.0}), std::nullopt}};
  CHECK_THROWS_WITH(nominal_element_commands(load_on_actuator, {0}), Contains("must not have a load profile"));

  // design_switch_times(body, actuator, rotation_rad, torque_limit_Nm, modes)
  CHECK_THROWS_WITH(design_switch_times(body, 5, 3.0, 1.0, 1),
                    Contains("actuator = 5 is not an element of the body (0..1)"));
  CHECK_THROWS_WITH(design_switch_times(body, 1, 3.0, 1.0, 1), Contains("must be a torque"));  // a thruster
  CHECK_THROWS_WITH(design_switch_times(body, 0, -1.0, 1.0, 1), Contains("rotation_rad = -1"));
  const FlexibleBody off_centre(Beam(BeamProperties::uniform(1.0, 1.0, 1.0)), 2,
                                {{"tau", ForceElement::Type::Torque, 0.3, {0.0, 0.0}, false}});
  CHECK_THROWS_WITH(design_switch_times(off_centre, 0, 1.0, 1.0, 1), Contains("must act at o"));
}

TEST_CASE("closed loop, weights and metrics validate sizes", "[control]") {
  const FlexibleBody body = beam_with_actuators();
  const TwoSecondManeuver nominal;
  const FirstOrderModel model(body, nominal, zero(), {0, 1});
  TvlqrResult unsolved;
  CHECK_THROWS_WITH(simulate_closed_loop_first_order(model, unsolved, {}, ClosedLoopOptions{}),
                    Contains("was not solved"));
  TvlqrOptions o;
  o.grid_step_s = 0.5;
  const TvlqrResult law =
      solve_tvlqr(model, 0.0, 2.0, vibration_weight(body, 1.0, 1.0, 1.0), Eigen::MatrixXd::Identity(2, 2), o);
  REQUIRE(law.ok());
  ClosedLoopOptions co;
  co.limits = Eigen::Vector3d(1.0, 1.0, 1.0);
  CHECK_THROWS_WITH(simulate_closed_loop_first_order(model, law, {}, co),
                    Contains("expected 2 actuator limits (or none), got 3"));
  co.limits = Eigen::Vector2d(1.0, 0.0);
  CHECK_THROWS_WITH(simulate_closed_loop_first_order(model, law, {}, co), Contains("limits(1) = 0, must be > 0"));
  CHECK_THROWS_WITH(vibration_weight(body, -1.0, 1.0, 1.0), Contains("w_elastic = -1"));
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(3, 0.0, 1.0);
  CHECK_THROWS_WITH(response_metrics(body, t, Eigen::MatrixXd::Zero(3, 4), Eigen::MatrixXd::Zero(3, 5), Eigen::MatrixXd()),
                    Contains("expected z of size 3 x 5, got 3 x 4"));
}
