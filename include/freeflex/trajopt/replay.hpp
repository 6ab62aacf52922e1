#pragma once
// An optimized maneuver played back open loop: the zero-order (rigid) model integrated by
// CVODES from the problem's initial state under the solution's commands u(t). The
// commands are only piecewise smooth (linear or quadratic between knots), so the
// integrator restarts at every knot. What the replay misses the target by measures how
// well the collocation solution satisfies the dynamics between its points.
#include "freeflex/sim/integrator.hpp"
#include "freeflex/trajopt/solve.hpp"

namespace freeflex {

/// States [Rx, Ry, θ, Rx', Ry', θ'] at t = 0 and t = T (the solution's duration).
/// Throws std::invalid_argument when the result has no trajectory; a numerical failure
/// is reported in the IntegrationResult.
IntegrationResult replay_open_loop(const FlexibleBody& body, const ManeuverProblem& problem,
                                   const TrajoptResult& result, const IntegratorOptions& options);

}  // namespace freeflex
