#pragma once
// A rigid maneuver flown open loop by some of the body's actuators: the nominal motion
// that the perturbation solution and the controllers are built about, and the commands
// that fly it (from trajectory optimization: trajopt/solve.hpp, flown_maneuver()).
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/model/loads.hpp"

namespace freeflex {

struct FlownManeuver {
  /// R0(t), θ0(t) over [0, duration_s].
  std::shared_ptr<const RigidTrajectory> motion;
  /// Element indices of the actuators the commands drive.
  std::vector<int> actuators;
  /// Their commands u(t) on [0, duration_s] [N or N m]: a callback that writes
  /// actuators.size() entries into the buffer it is handed.
  std::function<void(const Instant&, Eigen::Ref<Eigen::VectorXd>)> commands;
  /// Times where the commands may jump or kink.
  std::vector<double> breakpoints;
  double duration_s = 0.0;

  /// The loads with these commands added on the actuators (nothing after duration_s).
  Excitation driving(const Excitation& loads) const;
  /// The motion continued at rest (its final rates) after duration_s.
  std::shared_ptr<const RigidTrajectory> nominal() const;
};

}  // namespace freeflex
