#pragma once
// Optimal rigid maneuvers by direct collocation (trajopt/collocation.hpp) solved with
// Ipopt: exact sparse Jacobian, exact sparse Hessian of the Lagrangian
// (hessian_approximation exact), gradient-based NLP scaling (Ipopt's default), MUMPS
// with its internal scaling off (mumps_scaling 0: robust to boundary conditions that
// repeat what the dynamics fix, and faster), a 20% workspace margin (mumps_mem_percent
// 20; Ipopt raises it on demand) and the AMF ordering (mumps_pivot_order 2: linear cost
// in N), and the constraint multipliers started at zero (constr_mult_init_max 0: no
// least-squares estimate, which costs a factorization of its own). TrajoptOptions::
// ipopt_options override any of these. Mesh-refinement rounds, and the full mesh after a
// rigid problem's coarse start, start at mu_init 1e-6 from the interpolated solution and
// the bound multipliers of the mesh before (CollocationNlp::carried_bound_multipliers,
// Ipopt's warm_start_init_point).
//
//   TrajoptResult r = solve_maneuver(body, problem, options);
//   if (r.ok()) r.trajectory->at(Instant::at(t));  // a RigidTrajectory
//
// Bad input (see validate() in trajopt/problem.hpp) throws std::invalid_argument before
// any work; a numerical outcome (infeasible, iteration limit, ...) is a result with a
// status and a message, never an exception.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/sim/maneuver.hpp"
#include "freeflex/trajopt/problem.hpp"
#include "freeflex/trajopt/trajectory.hpp"

namespace freeflex {

enum class TrajoptStatus {
  Solved,            ///< Ipopt Solve_Succeeded
  SolvedAcceptable,  ///< Ipopt Solved_To_Acceptable_Level
  Infeasible,        ///< Ipopt Infeasible_Problem_Detected: converged to a point of local infeasibility
  MaxIterations,     ///< Ipopt Maximum_Iterations_Exceeded (or CPU time)
  Failed,            ///< anything else (restoration failure, too small steps, evaluation error, ...)
};

template <>
struct EnumNames<TrajoptStatus> {
  static constexpr const char* what = "trajectory optimization status";
  static constexpr std::array<std::pair<TrajoptStatus, const char*>, 5> names{
      {{TrajoptStatus::Solved, "solved"},
       {TrajoptStatus::SolvedAcceptable, "solved_acceptable"},
       {TrajoptStatus::Infeasible, "infeasible"},
       {TrajoptStatus::MaxIterations, "max_iterations"},
       {TrajoptStatus::Failed, "failed"}}};
};

/// One solve on one mesh (mesh refinement makes several).
struct MeshRound {
  int intervals = 0;
  int iterations = 0;
  double objective = 0.0;
  double max_defect = 0.0;
  double max_error_estimate = 0.0;  ///< max over intervals of CollocationTrajectory::interval_errors
};

struct TrajoptResult {
  TrajoptStatus status = TrajoptStatus::Failed;
  std::string message;  ///< Ipopt's status in words, with "not a solution" when not ok()
  /// Solved or SolvedAcceptable: the arrays below are an optimum of the last NLP.
  bool ok() const { return status == TrajoptStatus::Solved || status == TrajoptStatus::SolvedAcceptable; }

  double objective = 0.0;    ///< J at the returned point
  int iterations = 0;        ///< Ipopt iterations, summed over mesh rounds
  /// Iterations of the coarse rigid solve of the starting point (TrajoptOptions::
  /// coarse_start; 0: none was solved) and whether it was used (it is not when that solve
  /// did not succeed).
  int warm_start_iterations = 0;
  bool warm_started = false;
  double solve_time_s = 0.0; ///< wall time of the whole call
  double duration_s = 0.0;   ///< T
  double max_defect = 0.0;   ///< max |collocation defect| at the returned point (HS: incl. midpoint rows)
  double max_error_estimate = 0.0;  ///< max interval error estimate of the returned trajectory
  Transcription transcription = Transcription::HermiteSimpsonCompressed;
  LinearSolver linear_solver = LinearSolver::Ldlt;
  int intervals = 0;                ///< N of the final mesh
  std::vector<MeshRound> rounds;    ///< first solve, then each refinement

  Eigen::VectorXd t;      ///< N+1 knot times [s]
  Eigen::MatrixXd x;      ///< (N+1) x 6 knot states (rigid part)
  /// (N+1) x (4 + 2n) elastic knot states x1 (trajopt/elastic_dynamics.hpp); 0 columns
  /// without problem.elastic.
  Eigen::MatrixXd x_elastic;
  /// With problem.elastic: E_vib(T) of the optimizer's elastic state (eq. 6.8) [J] and the
  /// largest |Φ q| at either end of the beam over the collocation points [m].
  double terminal_vibration_energy_J = 0.0;
  double peak_tip_deflection_m = 0.0;
  /// With problem.elastic: ω_j [rad/s] of the elastic modes the problem holds (ascending),
  /// the longest mesh interval h [s], and the modes (indices into mode_frequencies) that
  /// the mesh does not resolve, ω_j h > max_resolved_omega_h: the collocation's version
  /// of such a mode oscillates at the wrong frequency, so terminal_vibration_energy_J does
  /// not describe that mode's true motion (docs/theory.md section 11, "Coordinates").
  Eigen::VectorXd mode_frequencies;
  double max_interval_s = 0.0;
  std::vector<int> unresolved_modes;
  static constexpr double max_resolved_omega_h = 2.0;
  /// ∫ uᵀ W u dt of the returned commands (W: the problem's energy_weights), whatever the
  /// objective; exact for the transcription's piecewise-polynomial controls.
  double control_energy = 0.0;
  Eigen::MatrixXd u;      ///< (N+1) x nu knot controls
  Eigen::VectorXd t_mid;  ///< Hermite–Simpson only: N midpoint times, rigid states, controls
  Eigen::MatrixXd x_mid;
  Eigen::MatrixXd u_mid;

  /// The continuous trajectory the solution stands for (also for a failed solve: the
  /// last iterate). Null only if Ipopt returned no point at all.
  std::shared_ptr<const CollocationTrajectory> trajectory;
  /// u(t) of `trajectory` (zero outside [0, T]); zeros if there is no trajectory.
  Eigen::VectorXd control_at(double t_s) const;

  /// With options.derivative_test != "none": errors Ipopt's derivative checker reported
  /// (0 when it printed "No errors detected"); -1 when the checker did not run.
  int derivative_test_errors = -1;
  std::string log;  ///< Ipopt's output when options.keep_log or derivative_test is set
};

TrajoptResult solve_maneuver(const FlexibleBody& body, const ManeuverProblem& problem, const TrajoptOptions& options);

/// What result.unresolved_modes means for the user, with the remedy (hold fewer modes or
/// use a finer mesh); empty when every mode the problem holds is resolved.
std::string unresolved_modes_message(const TrajoptResult& result);

/// The solution flown open loop by the problem's actuators: its motion, commands (zero
/// after the duration) and knots, for the perturbation solution and the controllers.
/// Throws std::invalid_argument when the result is not ok() or has no trajectory.
FlownManeuver flown_maneuver(const TrajoptResult& result, const ManeuverProblem& problem);

}  // namespace freeflex
