#pragma once
// Simulations of the three models (docs/theory.md section 8). Every run starts at rest
// at the origin unless an initial state is given, and reports totals z = [Rx, Ry, θ, q]
// and rates at the output times.
#include <memory>
#include <string>

#include <Eigen/Dense>

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex {

struct SimulationOptions {
  IntegratorOptions integrator;
  double duration_s = 3.0;       ///< from t = 0
  double output_step_s = 0.005;  ///< spacing of the output times
  /// Spacing of the samples of the zero-order motion handed to the first-order model
  /// (quintic Hermite between samples); the output step if smaller. 0: automatic,
  /// trajectory_step(): 1 ms, or 5 ms with first_order_solver = Taylor (whose steps end at
  /// every sample, where the interpolant's third derivative jumps; at 5 ms the moment
  /// example at NOA 20 takes 30% less work and is as accurate, docs/benchmarks.md).
  double trajectory_step_s = 0.0;
  /// What the integrator integrates (docs/theory.md section 8): the state [z, z'] itself
  /// (Physical); the same with q taken to the modes at rest, q = Ψ η (RestModes, the full
  /// model only, and not with a prescribed motion: the same steps as Physical, a
  /// right-hand side whose cost grows as n instead of n², a third less time at NOA 20 and
  /// a quarter of it at NOA 40, nothing gained at NOA 4-10); or modal amplitudes that
  /// leave the free elastic oscillation out (Modal). Same equations; the modal form takes
  /// far fewer steps when the oscillation is nearly free (the first-order model always;
  /// the full model at rotation rates well below the first elastic frequency) and more
  /// when fast rotation couples the modes. Results are always reported as [z, z'].
  enum class Variables { Physical, Modal, RestModes };
  Variables full_variables = Variables::Physical;      ///< of the full nonlinear model
  Variables first_order_variables = Variables::Modal;  ///< of the first-order model
  /// How the perturbation solution's first-order model is integrated: by `integrator`
  /// in `first_order_variables`, or by Taylor series of the linear model in body
  /// coordinates with exact exponentials where its coefficients are constant (docs/theory.md
  /// section 8; much faster at many functions, for models whose coefficients are linear in
  /// the nominal rate squared, accelerations and commands; others fail with the reason).
  /// `integrator.rtol` and `atol` set the Taylor steps too.
  enum class FirstOrderSolver { Integrator, Taylor };
  FirstOrderSolver first_order_solver = FirstOrderSolver::Integrator;
  /// A run ends with status out_of_range when the elastic deflection |u(x)| somewhere on
  /// the beam exceeds this fraction of the beam's length (an inextensible beam cannot bend
  /// further than its length: the response has grown without bound). Checked at output times.
  double max_deflection_ratio = 1.0;
  /// Integrate the work done on the body along the full model's solution (SimulationResult::
  /// work_J, the energy balance of the range report). It leaves the states unchanged but
  /// costs CPU time (the paper's force pulse: 16 → 32 ms, moment pulse: 46 → 63 ms in
  /// bench_spinup), so it is off unless asked for; `freeflex run` asks for it.
  bool energy_balance = false;
};

/// Every setting out of range, those of `integrator` as "integrator.rtol"; empty when valid.
std::vector<FieldProblem> problems(const SimulationOptions& options);
/// Throws std::invalid_argument listing problems(options); the defaults are valid.
void validate(const SimulationOptions& options);

struct SimulationResult {
  IntegrationStatus status = IntegrationStatus::Failed;
  std::string message;     ///< reason of a failure, with the time reached
  bool ok() const { return status == IntegrationStatus::Completed; }
  Eigen::VectorXd t;       ///< output times reached
  Eigen::MatrixXd z;       ///< totals [Rx, Ry, θ, q], one row per time
  Eigen::MatrixXd z_dot;   ///< their rates
  long rhs_evaluations = 0;
  long steps = 0;
  double wall_time_s = 0.0;
  /// Full model only: work done on the body from t = 0 to each output time by the loads,
  /// the damping and (prescribed motion) the force that holds the motion; the energy
  /// balance is energy(t) - energy(0) = work_J(t). Empty for the perturbation solution and
  /// for the full model in modal variables (their long steps would alias the power).
  Eigen::VectorXd work_J;
};

/// Rows Φ(x) at `points` equally spaced points of the beam, ends included: the elastic
/// deflection u(x) = Φ(x) q there is (this matrix) q.
Eigen::MatrixXd deflection_sampler(const FlexibleBody& body, int points = 41);

/// Output times 0, dt, 2 dt, ..., duration (the last one exactly).
std::vector<double> output_times(const SimulationOptions& options);
/// The spacing of the zero-order samples options asks for: trajectory_step_s, or when it
/// is 0 the automatic one (1 ms; 5 ms with the Taylor first-order solver); not above
/// the output step.
double trajectory_step(const SimulationOptions& options);
/// The options of a perturbation run whose nominal motion other computations reuse (a
/// TV-LQR design, a first-order model): an automatic trajectory step is resolved to the
/// integrator's 1 ms whatever the first-order solver (Taylor's coarser default serves its
/// own steps only).
SimulationOptions with_reusable_nominal(SimulationOptions options);

/// Full nonlinear model (eq. 6.2) under the excitation's commands.
SimulationResult simulate_full(const FlexibleBody& body, const Excitation& excitation, const SimulationOptions& options,
                               const Eigen::VectorXd& x_initial = Eigen::VectorXd());

struct PerturbationResult {
  SimulationResult total;       ///< R0 + R1, θ0 + θ1, q (and rates)
  SimulationResult zero_order;  ///< the rigid motion alone (q columns zero)
  std::shared_ptr<const RigidTrajectory> nominal;  ///< what the first-order model used
  long first_order_rhs_evaluations = 0;
};

/// Zero-order simulation, its rigid trajectory, then the first-order simulation about it
/// with u1 = 0 (eq. 7.3). The excitation is the nominal (zero-order) loading.
PerturbationResult simulate_perturbation(const FlexibleBody& body, const Excitation& excitation,
                                         const SimulationOptions& options);

/// The first-order simulation about a given rigid trajectory (from the optimizer, say),
/// with u1 = 0; totals add the trajectory. The excitation gives the nominal commands.
PerturbationResult simulate_perturbation_about(const FlexibleBody& body, const Excitation& excitation,
                                               std::shared_ptr<const RigidTrajectory> nominal,
                                               const SimulationOptions& options);

/// An estimate of a simulation's global (accumulated) integration error, from a second
/// run of the same model with tighter tolerances (docs/theory.md section 8): the largest
/// difference over the common output times, per group of coordinates. When the error
/// falls in proportion to the tolerance, the difference is (1 - 1/kErrorEstimateFactor)
/// of the first run's error (90%); when it falls as its square root, 68%.
struct GlobalErrorEstimate {
  bool available = false;  ///< false: the second run failed (see message) or was not made
  std::string message;     ///< why it is not available
  double rtol = 0.0, atol = 0.0;  ///< of the second run
  double R_m = 0.0;        ///< max |ΔRx|, |ΔRy|
  double theta_rad = 0.0;  ///< max |Δθ|
  double q = 0.0;          ///< max |Δq_i|
  double rates = 0.0;      ///< max over every rate (m/s, rad/s, 1/s)
  double worst_time_s = 0.0;  ///< where the largest of R, θ and q differences is
  long rhs_evaluations = 0;   ///< of the second run
  double wall_time_s = 0.0;   ///< of the second run
};

/// The second run's tolerances divide the first's by this factor.
inline constexpr double kErrorEstimateFactor = 10.0;
/// The tolerances of the second run: rtol and atol over kErrorEstimateFactor, rtol not
/// below 1e-14 (CVODES's error test needs some room above the unit round-off); no progress.
SimulationOptions error_reference_options(const SimulationOptions& options);
/// The estimate from a run and the second run over the same output times (`reference`
/// made with error_reference_options(options)). Not available when either failed.
GlobalErrorEstimate compare_runs(const SimulationResult& run, const SimulationResult& reference,
                                 const SimulationOptions& reference_options);

template <>
struct EnumNames<SimulationOptions::Variables> {
  static constexpr const char* what = "integration variables";
  static constexpr std::array<std::pair<SimulationOptions::Variables, const char*>, 3> names{
      {{SimulationOptions::Variables::Physical, "physical"},
       {SimulationOptions::Variables::Modal, "modal"},
       {SimulationOptions::Variables::RestModes, "rest_modes"}}};
};

template <>
struct EnumNames<SimulationOptions::FirstOrderSolver> {
  static constexpr const char* what = "first-order solver";
  static constexpr std::array<std::pair<SimulationOptions::FirstOrderSolver, const char*>, 2> names{
      {{SimulationOptions::FirstOrderSolver::Integrator, "integrator"},
       {SimulationOptions::FirstOrderSolver::Taylor, "taylor"}}};
};

}  // namespace freeflex
