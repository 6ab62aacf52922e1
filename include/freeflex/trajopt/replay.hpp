#pragma once
// An optimized maneuver played back open loop: the zero-order (rigid) model integrated by
// CVODES from the problem's initial state under the solution's commands u(t). The
// commands are only piecewise smooth (linear or quadratic between knots), so the
// integrator restarts at every knot. What the replay misses the target by measures how
// well the collocation solution satisfies the dynamics between its points.
#include "freeflex/sim/integrator.hpp"
#include "freeflex/trajopt/solve.hpp"

#include <string>

namespace freeflex {

/// States [Rx, Ry, θ, Rx', Ry', θ'] at t = 0 and t = T (the solution's duration).
/// Throws std::invalid_argument when the result has no trajectory; a numerical failure
/// is reported in the IntegrationResult.
IntegrationResult replay_open_loop(const FlexibleBody& body, const ManeuverProblem& problem,
                                   const TrajoptResult& result, const IntegratorOptions& options);

/// The optimizer's final state against the commands flown on the model it optimized: the
/// zero-order model integrated by the Verner 9(8) pair (rtol 1e-10) under the solution's commands, from
/// its initial state, compared with the collocation's state at T. A miss larger than
/// `relative_limit` of the maneuver's scale (position: max(|ΔR|, beam length); attitude:
/// max(|Δθ|, 1 rad)) is flagged: the mesh does not resolve the rigid motion.
struct ReplayCheck {
  bool ok = false;              ///< the replay integrated (else message says why)
  bool flagged = false;         ///< the miss is larger than relative_limit of the scale
  std::string message;          ///< the failure, or when flagged what the miss means
  double position_miss_m = 0;   ///< |R_replay(T) − R_collocation(T)|
  double theta_miss_rad = 0;    ///< |θ_replay(T) − θ_collocation(T)|
  double rate_miss = 0;         ///< max |rate difference| at T (m/s and rad/s)
  double position_scale_m = 0;  ///< max(|ΔR| of the maneuver, beam length)
  double theta_scale_rad = 0;   ///< max(|Δθ| of the maneuver, 1 rad)
  static constexpr double relative_limit = 1e-2;
};

/// Throws std::invalid_argument when the result has no trajectory.
ReplayCheck check_replay(const FlexibleBody& body, const ManeuverProblem& problem, const TrajoptResult& result);

}  // namespace freeflex
