#pragma once
// Vibration suppression in one call: the chain maneuver → nominal motion → first-order
// LTV model → TV-LQR → closed loop, on the first-order and on the full nonlinear model,
// with the open loop it is compared against.
//
//   1. the nominal motion: the maneuver's, continued at rest after it ends, or (without
//      a maneuver) the zero-order motion of the loads;
//   2. open loop: the perturbation solution and the full model under the loads and the
//      maneuver's commands;
//   3. the first-order model about the nominal motion, with the feedback actuators as
//      its inputs, and the TV-LQR designed on it over [0, horizon_s];
//   4. closed loop: u = u0 + u1 on every feedback actuator, u0 the maneuver's command and
//      u1 = −K(t) x1 + u_ff(t), saturated at the limits, on the first-order model and on
//      the full model, over [0, until_s].
// Times in s, commands in N or N m.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/tvlqr.hpp"
#include "freeflex/enum_names.hpp"
#include "freeflex/sim/maneuver.hpp"
#include "freeflex/sim/simulate.hpp"

namespace freeflex {

/// What to suppress and with what.
struct SuppressionProblem {
  Excitation loads;                       ///< every element's load profile (actuators have none)
  std::optional<FlownManeuver> maneuver;  ///< flown open loop; without one the loads' motion is the nominal
  std::vector<int> actuators;             ///< feedback actuators (element indices; must include the maneuver's)
  Eigen::VectorXd limits;                 ///< |u| bound per feedback actuator (infinity: none)
  Eigen::MatrixXd Q;                      ///< TV-LQR state weight (2N x 2N, symmetric PSD)
  Eigen::MatrixXd R;                      ///< TV-LQR input weight (m x m, symmetric PD)
  double horizon_s = 3.0;                 ///< TV-LQR over [0, horizon_s]
  double until_s = 3.0;                   ///< open- and closed-loop runs over [0, until_s]
};

enum class SuppressionPhase { OpenLoop, Tvlqr, ClosedLoop };

struct SuppressionResult;

/// Settings of the chain.
struct SuppressionOptions {
  /// The open-loop runs (tolerances, output and trajectory steps; the duration is until_s);
  /// the closed-loop runs share the output step.
  SimulationOptions simulation;
  TvlqrOptions tvlqr;                                       ///< the loads' times are added as breakpoints
  IntegratorOptions closed_loop = closed_loop_integrator();  ///< CVODES settings of the closed-loop runs
  /// The first-order closed loop's method and Gauss steps (ClosedLoopOptions); the full
  /// model's closed loop is CVODES's with closed_loop.
  ClosedLoopMethod closed_loop_first_order_method = ClosedLoopMethod::Cvodes;
  int closed_loop_gauss_steps = ClosedLoopOptions{}.gauss_steps;
  /// Optional, for progress reports (must not throw): a phase begins (done = false; its
  /// span in simulated or swept seconds is `total_s`) or ends (done = true, `so_far`
  /// holds its results).
  std::function<void(SuppressionPhase phase, bool done, double total_s, const SuppressionResult& so_far)> on_phase;
  /// Optional: how far the current phase has got, out of its total_s.
  std::function<void(SuppressionPhase phase, double covered_s)> progress;
};

/// Throws std::invalid_argument naming the first setting out of range; the defaults are
/// valid.
void validate(const SuppressionOptions& options);

struct SuppressionResult {
  enum class Status {
    Solved,            ///< every run completed
    HorizonTooShort,   ///< the maneuver outlasts the horizon: no feedback was designed
    OpenLoopFailed,    ///< an open-loop run failed: nothing was designed
    TvlqrFailed,       ///< the TV-LQR solve failed
    ClosedLoopFailed,  ///< a closed-loop run failed (the other's results stand)
  };
  Status status = Status::OpenLoopFailed;
  std::string message;
  bool ok() const { return status == Status::Solved; }

  std::shared_ptr<const RigidTrajectory> nominal;  ///< the motion the controller is built about
  /// The nominal commands u0(t) of the feedback actuators (the maneuver's, zero after it
  /// and without one), as the closed loops add them to the feedback.
  ActuatorCommandFunction u0;
  PerturbationResult open_loop_first_order;        ///< open loop, perturbation solution
  SimulationResult open_loop_full;                 ///< open loop, full model
  TvlqrResult law;
  ClosedLoopResult closed_loop_first_order;
  ClosedLoopResult closed_loop_full;
};

/// The maneuver's commands as the nominal commands u0 of the feedback actuators (element
/// indices `actuators`, which include the maneuver's): zero on the others and once the
/// maneuver has ended.
ActuatorCommandFunction maneuver_actuator_commands(const FlownManeuver& maneuver, const std::vector<int>& actuators);

/// Runs the chain. Throws std::invalid_argument (before any work) for sizes that do not
/// match the body, a horizon or end out of range, weights that are not PSD / PD, or
/// options out of range; numerical failure ends the chain with its status and reason.
SuppressionResult suppress_vibration(const FlexibleBody& body, const SuppressionProblem& problem,
                                     const SuppressionOptions& options = {});

template <>
struct EnumNames<SuppressionResult::Status> {
  static constexpr const char* what = "suppression status";
  static constexpr std::array<std::pair<SuppressionResult::Status, const char*>, 5> names{
      {{SuppressionResult::Status::Solved, "solved"},
       {SuppressionResult::Status::HorizonTooShort, "horizon_too_short"},
       {SuppressionResult::Status::OpenLoopFailed, "open_loop_failed"},
       {SuppressionResult::Status::TvlqrFailed, "tvlqr_failed"},
       {SuppressionResult::Status::ClosedLoopFailed, "closed_loop_failed"}}};
};

template <>
struct EnumNames<SuppressionPhase> {
  static constexpr const char* what = "suppression phase";
  static constexpr std::array<std::pair<SuppressionPhase, const char*>, 3> names{
      {{SuppressionPhase::OpenLoop, "open_loop"}, {SuppressionPhase::Tvlqr, "tvlqr"},
       {SuppressionPhase::ClosedLoop, "closed_loop"}}};
};

}  // namespace freeflex
