#pragma once
// Rigid maneuvers posed for trajectory optimization: what to move where, under which
// actuator limits, at which cost; and how to transcribe and solve it. SI units and
// radians throughout: commands in N (forces, thrusters) or N m (torques), times in s.
//
// The plant is the zero-order (rigid) model, docs/theory.md eq. 6.3, see
// trajopt/rigid_dynamics.hpp, and with `elastic` also the first-order elastic motion
// about it (trajopt/elastic_dynamics.hpp). The cost is
//   J = w_energy ∫ Σ_k W_k u_k² dt + w_time T + w_smooth ∫ Σ_k u_k'² dt + w_vibration E_vib(T)
// over t in [0, T], T fixed (duration_s) or free in [t_min_s, t_max_s].
#include <algorithm>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/enum_names.hpp"
#include "freeflex/validation.hpp"

namespace freeflex {

class CollocationTrajectory;

struct ManeuverProblem {
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  static constexpr double inf = std::numeric_limits<double>::infinity();

  /// u_k commands element actuators[k] of the body (distinct indices).
  std::vector<int> actuators;
  /// Command bounds, one entry per actuator; ±infinity for none. u_min <= u_max.
  Eigen::VectorXd u_min, u_max;
  /// Optional rate bounds |u_k'| <= du_max(k) [N/s or N m/s], > 0 (infinity: none).
  std::optional<Eigen::VectorXd> du_max;
  /// Boundary states [Rx, Ry, θ, Rx', Ry', θ'] at t = 0 and t = T (rest to rest by default).
  Vector6d x_initial = Vector6d::Zero();
  Vector6d x_final = Vector6d::Zero();
  /// Bounds on the state strictly between the ends (none by default).
  Vector6d x_min = Vector6d::Constant(-inf);
  Vector6d x_max = Vector6d::Constant(inf);

  /// Fixed duration T = duration_s, or free T in [t_min_s, t_max_s] starting from
  /// duration_s (clamped into the bounds) unless an initial guess brings its own.
  bool free_time = false;
  double duration_s = 1.0;
  double t_min_s = 0.1;
  double t_max_s = 10.0;

  /// Objective weights (>= 0, at least one > 0; w_time needs free_time).
  double w_energy = 1.0;
  double w_time = 0.0;
  double w_smooth = 0.0;
  /// Diagonal W of the energy term, one entry >= 0 per actuator; empty means all ones.
  Eigen::VectorXd energy_weights;
  /// Commands start and end at zero (u(0) = u(T) = 0; needs 0 within [u_min, u_max]): a
  /// command cut at T releases the quasi-static deflection of every mode, modelled or not.
  bool zero_end_commands = false;

  /// Elastic modes inside the problem (docs/theory.md section 11): the state also holds
  /// the first-order elastic motion about the rigid one, from rest at t = 0.
  bool elastic = false;
  /// With elastic: the elastic coordinates of the problem: all_modes (-1), the body's own
  /// q (the first-order model itself); or m >= 1, its first m elastic modes at rest (a
  /// modal truncation: modes the mesh cannot resolve are left out, docs/theory.md).
  int elastic_modes = -1;
  /// With elastic: the first `modes_at_rest` elastic modes that the actuators excite end
  /// at rest, [ω_j η_j(T), η_j'(T)] = 0 (mass-normalized modes at rest, eq. 4.1); all_modes:
  /// every elastic mode, q(T) = q'(T) = 0; 0: none.
  static constexpr int all_modes = -1;
  int modes_at_rest = 0;
  /// With elastic: weight (>= 0) on the residual vibration energy E_vib(T) [J], eq. 6.8.
  double w_vibration = 0.0;
  /// With elastic: |Φ(x) q| <= tip_deflection_limit_m [m] at both ends of the beam at every
  /// collocation point (knots and midpoints; the compressed form: knots). > 0; inf: none.
  double tip_deflection_limit_m = inf;
};

/// How the continuous problem becomes an NLP (see trajopt/collocation.hpp).
enum class Transcription {
  Trapezoidal,     ///< states at knots, controls piecewise linear; O(h²)
  HermiteSimpson,  ///< separated form, states and controls at knots and midpoints; O(h⁴)
  /// Same discretization and solution as HermiteSimpson, with the midpoint states
  /// eliminated (x_c from the interpolation formula): a KKT system ~40% smaller.
  HermiteSimpsonCompressed,
};

template <>
struct EnumNames<Transcription> {
  static constexpr const char* what = "transcription";
  static constexpr std::array<std::pair<Transcription, const char*>, 3> names{
      {{Transcription::Trapezoidal, "trapezoidal"},
       {Transcription::HermiteSimpson, "hermite_simpson"},
       {Transcription::HermiteSimpsonCompressed, "hermite_simpson_compressed"}}};
};

/// Which sparse symmetric indefinite factorization Ipopt's KKT systems get.
enum class LinearSolver {
  /// freeflex's own multifrontal LDLᵀ (threshold 1x1/2x2 pivoting, AMD order; docs/
  /// benchmarks.md), served to Ipopt through its MA27 interface: Ipopt's ma27_* options
  /// apply to it. Several times faster than MUMPS on the reference BLAS at these sizes.
  Ldlt,
  Mumps,  ///< Ipopt's MUMPS (sequential, Debian's reference BLAS); its mumps_* options apply
};

template <>
struct EnumNames<LinearSolver> {
  static constexpr const char* what = "linear solver";
  static constexpr std::array<std::pair<LinearSolver, const char*>, 2> names{
      {{LinearSolver::Ldlt, "ldlt"}, {LinearSolver::Mumps, "mumps"}}};
};

/// True for the Hermite–Simpson forms (controls at interval midpoints too).
inline bool has_midpoints(Transcription t) { return t != Transcription::Trapezoidal; }

/// Where Ipopt starts. Priority: `solution`, then `control`, then the default (states
/// linearly interpolated from x_initial to x_final, controls zero clipped to the bounds).
struct InitialGuess {
  /// A previous solution (any mesh, any transcription): states, controls and duration
  /// are interpolated onto the new mesh.
  std::shared_ptr<const CollocationTrajectory> solution;
  /// A control history u(t) on [0, T] with nu entries, e.g. a pulse.
  std::function<Eigen::VectorXd(double t_s)> control;
  /// With `control`: states from a rollout of the dynamics under it (classical RK4, 8
  /// steps per interval) instead of the straight line from x_initial to x_final.
  bool rollout = false;
};

/// Settings of the transcription and of Ipopt. The defaults are those of a design file's
/// [maneuver] section.
struct TrajoptOptions {
  Transcription transcription = Transcription::HermiteSimpson;
  int intervals = 100;  ///< N >= 1, uniform mesh

  /// Mesh refinement rounds after the first solve (0: off). Each round estimates the
  /// local state error of every interval, e_k = max_i ∫_k |x_i' − f_i(x, u)| dt with the
  /// transcription's interpolants (5-point Gauss–Legendre), halves every interval with
  /// e_k > mesh_tolerance and re-solves warm-started from the interpolated solution.
  /// It stops early when no interval is flagged or the mesh would exceed max_intervals.
  int mesh_refinements = 0;
  double mesh_tolerance = 1e-6;  ///< [state units: m, rad, m/s, rad/s]
  int max_intervals = 5000;

  LinearSolver linear_solver = LinearSolver::Ldlt;  ///< Ipopt's KKT factorization
  bool verbose = false;  ///< Ipopt's log on stdout at print_level 5 (otherwise silent)
  double tol = 1e-8;     ///< Ipopt tol
  int max_iter = 3000;   ///< Ipopt max_iter
  /// Ipopt derivative_test: "none", "first-order", "second-order" or "only-second-order".
  /// Errors found are counted in TrajoptResult::derivative_test_errors.
  std::string derivative_test = "none";
  /// Any other Ipopt option, name and value as text; the value is read as the option's
  /// registered type (integer, number or string). Unknown names or unparsable values throw.
  std::vector<std::pair<std::string, std::string>> ipopt_options;
  InitialGuess guess;
  /// A problem given no guess (neither `guess.solution` nor `guess.control`) starts from
  /// a coarse solution: the rigid problem (a rigid problem itself, an elastic one its
  /// rigid counterpart, rigid_counterpart(): the same objective and limits without the
  /// elastic part) solved first on min(N, max(10, N / 8)) intervals with at most
  /// min(max_iter, 500) iterations, to coarse_start_tol. A rigid problem then continues from it as a
  /// mesh-refinement round does (Ipopt's mu_init 1e-6 and the coarse mesh's bound
  /// multipliers; skipped when the coarse mesh would not be coarser); an elastic one from the default barrier with its elastic state at
  /// rest. The slews of docs/benchmarks.md then need no large Hessian regularization
  /// (rigid, N = 100: 11-15 ms instead of 26-28; elastic NOA 6: 11 iterations instead of
  /// 19). If the coarse solve fails, the default straight line is used. Its iterations
  /// are reported in TrajoptResult::warm_start_iterations and its time is part of
  /// solve_time_s.
  bool coarse_start = true;
  static constexpr int coarse_start_max_iter = 500;
  /// Ipopt's tol for the coarse solve (or `tol`, if looser): it gives a starting point,
  /// whose optimum differs from the full mesh's by more than that anyway. On the rigid
  /// slews of docs/benchmarks.md 3-5 coarse iterations fewer than at 1e-8, the same fine
  /// ones but for one case (4 instead of 3).
  static constexpr double coarse_start_tol = 1e-4;
  /// The coarse mesh of coarse_start (used only when coarser than `intervals`).
  /// An eighth of the mesh: on the rigid slews of bench_trajopt 2.5-25% less work than a
  /// quarter (the fine mesh takes one or two iterations more, the coarse solve far less;
  /// docs/benchmarks.md).
  int coarse_start_intervals() const { return std::max(10, intervals / 8); }
  bool keep_log = false;  ///< copy Ipopt's log (of every solve) into TrajoptResult::log
  int log_level = 5;      ///< Ipopt print level of that copy (0-12)
};

/// Every problem found (sizes, ranges, orderings), in field order; empty when valid.
/// `element_count`: the force elements of the body the actuator indices refer to.
std::vector<FieldProblem> problems(const ManeuverProblem& problem, int element_count);
std::vector<FieldProblem> problems(const TrajoptOptions& options);
/// Throws std::invalid_argument listing every problem found.
void validate(const FlexibleBody& body, const ManeuverProblem& problem);
/// The same problem with the elastic part taken out (elastic, modes_at_rest, vibration
/// weight and tip bound cleared; the rest kept): its solution is the rigid optimum that a
/// vibration-aware maneuver is compared with.
ManeuverProblem rigid_counterpart(const ManeuverProblem& problem);
void validate(const TrajoptOptions& options);

}  // namespace freeflex
