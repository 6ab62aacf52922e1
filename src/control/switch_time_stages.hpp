#pragma once
// The switch-time design's two stages as solvers of one square system (the rest-to-rest
// and modal constraints in the interval durations): SLSQP (NLopt) on the closed form or
// on the first-order model, Newton's method on the first-order model, and the
// continuation that carries a closed-form root into the first-order model. Private to src/.
#include <vector>

#include "control/switch_time_model.hpp"

namespace freeflex::detail {

/// A point of a stage: interval durations, T = Σ Δ, the largest scaled constraint.
struct StageResult {
  bool feasible = false;
  std::vector<double> D;
  double T = 0.0, violation = 0.0;
};

/// SLSQP (NLopt) minimizing T under the 2k + 2 equality constraints from `start`: the
/// closed form (analytic gradients) or the first-order model (forward differences, one
/// simulation per column), at most `max_eval` evaluations.
StageResult run_slsqp(Problem& P, bool closed_form, const std::vector<double>& start, double tol, int max_eval);

/// Newton iterations on the first-order square system at most (each: a forward-difference
/// Jacobian, 2k + 2 simulations, and a backtracking line search).
inline constexpr int kNewtonIterations = 12;
/// Line-search trials per Newton iteration at most (steps 1, 1/2, ... 1/64).
inline constexpr int kLineSearchTrials = 7;
/// Newton (or SLSQP) solves of one continuation at most.
inline constexpr int kContinuationSolves = 8;

/// The first-order root that a closed-form root continues into. The closed form is the
/// first-order model's limit for a small rotation (Δθ and τmax scaled by λ → 0: the same
/// T*, rates λ times, so the θ0'² and θ0'' couplings vanish while the scaled constraints
/// keep their roots); the root is followed from λ = 0 to 1, at once when Newton (or
/// SLSQP, by `slsqp`) converges there, else in halved steps of λ with a secant predictor.
StageResult continue_to_first_order(Problem& P, const std::vector<double>& closed_form_root, double tol, bool slsqp,
                                    int max_eval);

}  // namespace freeflex::detail
