#pragma once
// Chattering of an optimized control: the signature of a singular arc that the
// transcription resolves badly (docs/theory.md section 11, "Chattering").
//
// Per actuator, the controls at the solution's points in time order (knots, and the
// midpoints of the Hermite–Simpson forms) give the differences d_i = u_{i+1} − u_i. A
// smooth control changes the sign of d only at its extrema, a bang-bang one at none; a
// chattering one at nearly every point. The check flags an actuator when the sign of d
// alternates at `min_run` consecutive points or more, each |d| above `threshold` times
// the actuator's range (u_max − u_min, or the largest |u| when unbounded).
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/trajopt/problem.hpp"

namespace freeflex {

struct TrajoptResult;

struct ChatteringOptions {
  int min_run = 4;          ///< consecutive sign alternations of the control's differences (>= 2)
  double threshold = 1e-3;  ///< each |d_i| at least this fraction of the actuator's range (> 0)
};
/// Throws std::invalid_argument naming the setting out of range.
void validate(const ChatteringOptions& options);

struct ChatteringReport {
  bool flagged = false;
  /// What was found, per flagged actuator: where and how long the alternation runs; or
  /// "no chattering" with the longest run.
  std::string message;
  std::vector<int> actuators;    ///< indices into problem.actuators, flagged ones
  std::vector<int> longest_run;  ///< per actuator: longest alternation run found
  std::vector<double> run_begin_s, run_end_s;  ///< per actuator: its time span (0, 0 if none)
  /// Suggested remedies: a smoothness weight w_smooth (clears the flag) that costs
  /// about 2% of the objective for a control with one full-range change per tenth of
  /// the duration; and a rate limit (per actuator) of one full-range change in T/20, which
  /// bounds the chatter's amplitude (on the slew: ±0.1 N instead of ±1 N) but need not
  /// remove it.
  double suggested_smooth_weight = 0.0;
  Eigen::VectorXd suggested_rate_limit;
  std::string remedy;  ///< the two suggestions in words (empty when not flagged)
};

/// Checks a solved maneuver's controls. `result` must hold a solution of `problem`.
ChatteringReport detect_chattering(const TrajoptResult& result, const ManeuverProblem& problem,
                                   const ChatteringOptions& options = {});

}  // namespace freeflex
