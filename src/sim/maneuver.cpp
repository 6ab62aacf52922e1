// A maneuver flown open loop (sim/maneuver.hpp): its commands added to the loads, and its
// motion continued at rest.
#include "freeflex/sim/maneuver.hpp"

namespace freeflex {

Excitation FlownManeuver::driving(const Excitation& loads) const {
  Excitation ex = loads;
  auto commands_of = commands;
  const std::vector<int> idx = actuators;
  const double end = duration_s;
  ex.add_commands = [commands_of, idx, end](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) {
    if (at.piece_mid > end) return;
    Eigen::VectorXd u(static_cast<Eigen::Index>(idx.size()));
    commands_of(at, u);
    for (std::size_t k = 0; k < idx.size(); ++k) c(idx[k]) += u(static_cast<Eigen::Index>(k));
  };
  ex.add_breakpoints = breakpoints;
  ex.add_end_time = duration_s;
  return ex;
}

std::shared_ptr<const RigidTrajectory> FlownManeuver::nominal() const {
  return std::make_shared<ExtendedTrajectory>(motion, duration_s);
}

}  // namespace freeflex
