// An optimized maneuver flown open loop on the zero-order model (trajopt/replay.hpp).
#include "freeflex/trajopt/replay.hpp"

#include <algorithm>
#include <sstream>
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

ReplayCheck check_replay(const FlexibleBody& body, const ManeuverProblem& problem, const TrajoptResult& result) {
  IntegratorOptions o;
  o.rtol = 1e-10;  // far below any miss worth a word: the integration's own error drops out
  o.atol = 1e-12;
  // The commands are a polynomial on each of the mesh's intervals, so the replay restarts
  // at every knot: an explicit pair starts each piece at its full order, where CVODES's
  // Adams climbs from order 1 with short steps (twice the instructions on the 80-interval
  // slew: 14.0 M against 6.7 M, docs/benchmarks.md).
  o.method = IntegratorOptions::Method::Verner98;
  const IntegrationResult rep = replay_open_loop(body, problem, result, o);
  ReplayCheck c;
  if (!rep.ok()) {
    c.message = "the replay of the optimized commands on the zero-order model failed: " + rep.message;
    return c;
  }
  c.ok = true;
  const Eigen::Index last = result.x.rows() - 1;
  const Eigen::VectorXd end = rep.x.row(rep.x.rows() - 1).transpose();
  const Eigen::VectorXd colloc = result.x.row(last).transpose();
  const Eigen::VectorXd start = result.x.row(0).transpose();
  c.position_miss_m = (end.head<2>() - colloc.head<2>()).norm();
  c.theta_miss_rad = std::abs(end(2) - colloc(2));
  c.rate_miss = (end.tail<3>() - colloc.tail<3>()).cwiseAbs().maxCoeff();
  c.position_scale_m = std::max((colloc.head<2>() - start.head<2>()).norm(), body.beam().length());
  c.theta_scale_rad = std::max(std::abs(colloc(2) - start(2)), 1.0);
  c.flagged = c.position_miss_m > ReplayCheck::relative_limit * c.position_scale_m ||
              c.theta_miss_rad > ReplayCheck::relative_limit * c.theta_scale_rad;
  if (c.flagged) {
    std::ostringstream os;
    os.precision(3);
    os << "the optimized commands flown on the zero-order model (Verner 9(8), rtol 1e-10) end "
       << c.position_miss_m << " m and " << c.theta_miss_rad << " rad from the optimizer's final state (more than "
       << 100 * ReplayCheck::relative_limit << "% of the maneuver's " << c.position_scale_m << " m or "
       << c.theta_scale_rad << " rad): the mesh of " << result.intervals
       << " intervals does not resolve the rigid motion; use more intervals or mesh_refinements";
    c.message = os.str();
  }
  return c;
}

}  // namespace freeflex
