// An optimized maneuver flown open loop on the zero-order model (trajopt/replay.hpp).
#include "freeflex/trajopt/replay.hpp"

#include <stdexcept>
#include <vector>

#include "freeflex/dynamics/zero_order.hpp"

namespace freeflex {

IntegrationResult replay_open_loop(const FlexibleBody& body, const ManeuverProblem& problem,
                                   const TrajoptResult& result, const IntegratorOptions& options) {
  if (!result.trajectory)
    throw std::invalid_argument("freeflex::replay_open_loop: the result has no trajectory (Ipopt returned no point)");
  const ZeroOrderModel zero(body);
  const auto& traj = *result.trajectory;
  Eigen::VectorXd commands = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(body.elements().size()));
  OdeSystem sys;
  sys.dim = 6;
  sys.rhs = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> xd) {
    const Eigen::VectorXd u = traj.control_at(at);  // the piece's own polynomial at a knot
    for (std::size_t k = 0; k < problem.actuators.size(); ++k)
      commands(problem.actuators[k]) = u(static_cast<Eigen::Index>(k));
    xd = zero.rhs(x, commands);
    return true;
  };
  const std::vector<double> knots(result.t.data(), result.t.data() + result.t.size());
  return integrate(sys, problem.x_initial, {0.0, result.duration_s}, knots, options);
}

}  // namespace freeflex
