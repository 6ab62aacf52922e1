#pragma once
// Bang-bang rest-to-rest rotation that leaves the first k excited elastic modes at rest.
//
// One torque actuator at o on a beam with S_o = 0 (o at the mass centre) turns the beam
// by Δθ with |τ| <= τmax. The rigid motion is θ0'' = τ/I_o (eq. 6.3); the rigid
// time-optimal answer is one switch, T* = 2 sqrt(I_o Δθ / τmax). The torque excites the
// modes that move θ (the antisymmetric ones on a uniform beam) through the forcing
// −Φ̃ᵀ θ0'' of the first-order model (eq. 7.2); with θ0' ≠ 0 the stiffness is also
// softened, K − θ0'² M (eq. 7.1).
//
// Structure (the classical time-optimal one for a rigid body plus k undamped modes):
// 2k+1 switches, signs +, −, +, ... (2k+2 intervals). The unknowns are the interval
// durations Δ_0..Δ_{2k+1} >= 0; the constraints are the rigid rest-to-rest conditions
// θ0(T) = Δθ, θ0'(T) = 0 and, for each targeted mode j, [ω_j η_j(T), η_j'(T)] = 0 (η_j
// the modal coordinate of the first-order state at T, mass-normalized modes of the rest
// model, eq. 4.1): 2k + 2 equations for 2k + 2 unknowns, so the designs are isolated
// roots, and the shortest root is the answer. On a flexible beam the shortest ones are
// near-rigid: the rigid switch at T*/2 with a cluster of short notches around it, T a
// fraction of a percent above T* (docs/theory.md section 12).
//
// Two stages:
//  1. closed form: modes frozen about rest and θ0'² neglected, so each mode is a forced
//     oscillator with residual amplitude ∝ |Σ_i c_i e^{iω t_i}| (c_i the torque jumps);
//     NLopt's SLSQP with analytic gradients, continued in the number of modes from the
//     rigid answer (the roots for k' − 1 modes, with one switch more inserted near each
//     switch of their first half and mirrored about T/2, start the runs for k'), plus
//     random antisymmetric starts; the distinct roots are sorted by T;
//  2. the first-order model itself (θ0'² softening and all couplings), simulated with
//     CVODES for every evaluation, gradients by forward differences: the shortest
//     closed-form roots are carried into it by a continuation in the size of the
//     rotation (Δθ and τmax scaled by λ from 0, where the closed form is exact, to 1),
//     each step solved by Newton's method on the square system by default, or by SLSQP;
//     the shortest first-order root is kept.
// The residual energy reported is that of the first-order simulation at T.
//
// Work, bounded before any work by k and the options (switch_time_work): closed-form
// evaluations at most (starts + 30 k²)(max_evaluations + 1), each O(k²) flops; first-order
// simulations at most refine_roots · simulations_per_unknown · (2k + 2) + 2 (1 for k = 0), each at most
// max_steps_per_simulation steps; and all their steps together at most max_total_steps.
// Spending a budget ends the design as not converged, with the reason.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/enum_names.hpp"
#include "freeflex/model/loads.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex {

/// θ0(t) of a bang-bang torque ±τmax at o (S_o = 0, R0 = 0): signs +, −, +, ... on the
/// intervals between 0, the switch times and the duration; at rest after it.
class BangBangRotation : public RigidTrajectory {
 public:
  /// Throws std::invalid_argument for I_o or τmax <= 0, or times not ascending in (0, T).
  BangBangRotation(double I_o, double torque_limit_Nm, std::vector<double> switch_times, double duration_s);
  RigidState at(const Instant& when) const override;
  double t_begin() const override { return 0.0; }
  double t_end() const override { return duration_; }
  std::vector<double> breakpoints() const override;
  /// The torque of the piece containing when.piece_mid (0 after the duration).
  double torque(const Instant& when) const;
  /// The torque as a Steps profile.
  TimeProfile profile() const;

 private:
  int piece(double piece_mid) const;
  double tau_max_, accel_, duration_;
  std::vector<double> t_;      // 0, switches, T
  std::vector<double> theta_, rate_;  // at each t_
};

/// Settings of the switch-time design; the problem (actuator, rotation, torque limit,
/// modes) is given to design_switch_times as arguments.
struct SwitchTimeOptions {
  double rtol = 1e-10;             ///< first-order simulations (Adams)
  double atol = 1e-13;
  /// Steps of each first-order simulation (IntegratorOptions::max_total_steps); 0: no limit.
  long max_steps_per_simulation = 0;
  /// Steps of all first-order simulations of one design together; 0: no limit.
  long max_total_steps = 0;
  /// Optional: the work budget every first-order simulation is charged to
  /// (IntegratorOptions::budget; a study's, shared with its other integrations). Once it
  /// is spent each simulation fails at once, and so does the design.
  std::shared_ptr<WorkBudget> budget;
  /// On the scaled constraints (each modal one is sqrt(E_j / E_rigid)): 1e-7 leaves
  /// E_j / E_rigid ~ 1e-14.
  double constraint_tolerance = 1e-7;
  int starts = 24;                 ///< random antisymmetric starts of the closed-form stage, in [1, 10000]
  int max_evaluations = 200;       ///< SLSQP evaluations per run, in [1, 100000]
  /// Closed-form roots carried into the first-order model at most, shortest first, in
  /// [1, 100]; roots more than 1% longer than the shortest first-order root found are not.
  int refine_roots = 4;
  /// First-order simulations per carried root and per unknown (2k + 2 unknowns), in
  /// [1, 10000]: a root that needs more is given up (Newton took 8 to 22 on the paper's beam).
  int simulations_per_unknown = 25;
  /// Stage 2's solver at each continuation step: Newton's method on the square system
  /// (forward-difference Jacobian; 32 simulations for k = 1 on the paper's beam) or NLopt
  /// SLSQP with the same gradients (minimizing T under the equality constraints; 731
  /// simulations there, so it needs max_evaluations >= 150 and simulations_per_unknown
  /// >= 185).
  enum class Refine { Newton, Slsqp } refine = Refine::Newton;
  /// Optional: called with the count of first-order simulations so far after each one
  /// starts (for progress reports); must not throw.
  std::function<void(int)> progress;
};

/// The most work design_switch_times(..., modes, options) may do (see the file comment).
struct SwitchTimeWork {
  long closed_form_evaluations = 0;  ///< (starts + 30 k²)(max_evaluations + 1)
  long simulations = 0;              ///< refine_roots · simulations_per_unknown · (2k + 2) + 2 (1 for k = 0)
  long steps = 0;                    ///< of all simulations together; 0: unbounded (no step limits set)
};
/// Throws std::invalid_argument for modes outside [0, 4] or options out of range.
SwitchTimeWork switch_time_work(int modes, const SwitchTimeOptions& options);

/// Throws std::invalid_argument naming the first setting out of range (the actuator is
/// checked against the body by design_switch_times); the defaults are valid.
void validate(const SwitchTimeOptions& options);

struct SwitchTimeResult {
  enum class Status { Solved, NotConverged };
  Status status = Status::NotConverged;
  std::string message;
  bool ok() const { return status == Status::Solved; }

  std::vector<double> switch_times;  ///< 2k+1 interior switch times [s]
  double duration_s = 0.0;           ///< T
  double rigid_duration_s = 0.0;     ///< T* = 2 sqrt(I_o Δθ / τmax)
  std::vector<double> closed_form_switch_times;  ///< stage 1
  double closed_form_duration_s = 0.0;
  double closed_form_residual_ratio = 0.0;  ///< stage-1 design simulated in the first-order model
  int closed_form_roots = 0;               ///< distinct closed-form roots found

  Eigen::VectorXd mode_frequencies_rad_s;  ///< the targeted modes (rest model)
  Eigen::VectorXd residual_energy_J;       ///< of each targeted mode at T (first-order model)
  double peak_rate_rad_s = 0.0;            ///< max θ0'
  double rigid_kinetic_peak_J = 0.0;       ///< ½ I_o θ0'max²
  double residual_ratio = 0.0;             ///< Σ residual_energy_J / rigid_kinetic_peak_J
  double final_angle_rad = 0.0;            ///< θ0(T)
  double final_rate_rad_s = 0.0;           ///< θ0'(T)
  long closed_form_evaluations = 0;         ///< work done (within switch_time_work)
  int simulations = 0;                      ///< first-order simulations, the final checks included
  long steps = 0;                           ///< their CVODES steps
  double wall_time_s = 0.0;

  TimeProfile torque_profile() const;  ///< needs the limit: ±τmax Steps (stored below)
  double torque_limit_Nm = 0.0;
};

/// The elastic modes of the model at rest (eq. 4.1, attitude `theta`) and those that
/// element `element` excites there: participation |vᵀ g| above 1e-8 of the largest. The
/// bang-bang design targets the first k of them; the design file is checked against them.
struct ExcitedModes {
  Eigen::MatrixXd M0;             ///< 𝕄0 at theta (N x N)
  Eigen::VectorXd eigenvalues;    ///< of (K0, 𝕄0): three rigid (round-off), then ω² ascending
  Eigen::MatrixXd eigenvectors;   ///< 𝕄0-normalized, one column per eigenvalue
  Eigen::VectorXd participation;  ///< vᵀ g of each elastic mode (size n)
  std::vector<int> excited;       ///< elastic modes (0 = the lowest) above the threshold
};
ExcitedModes excited_modes(const FlexibleBody& body, int element, double theta = 0.0);

/// Switch times of a rest-to-rest rotation by Δθ = rotation_rad > 0 [rad] with the torque
/// element `actuator` (|τ| <= torque_limit_Nm) that leave the first `modes` (k in [0, 4])
/// excited elastic modes at rest. Throws std::invalid_argument (before any work) if the
/// actuator is not an element of the body, not a torque, not at o, if S_o != 0, or for
/// Δθ, τmax, k or options out of range.
SwitchTimeResult design_switch_times(const FlexibleBody& body, int actuator, double rotation_rad,
                                     double torque_limit_Nm, int modes, const SwitchTimeOptions& options = {});

/// The first-order model's state at the end of a bang-bang rotation and the energy of
/// the first `modes` excited elastic modes in it.
struct BangBangResidual {
  IntegrationStatus status = IntegrationStatus::Failed;
  std::string message;
  bool ok() const { return status == IntegrationStatus::Completed; }
  Eigen::VectorXd omega_rad_s;     ///< targeted modes
  Eigen::VectorXd energy_J;        ///< ½(η'² + ω² η²) of each
  Eigen::VectorXd x1_end;          ///< first-order state at T
  double peak_rate_rad_s = 0.0;
  double rigid_kinetic_peak_J = 0.0;
};

/// Simulates the first-order model about BangBangRotation(I_o, τmax, switch_times, T)
/// with the torque on `actuator` (validated as in design_switch_times).
BangBangResidual bang_bang_residual(const FlexibleBody& body, int actuator, double torque_limit_Nm,
                                    const std::vector<double>& switch_times, double duration_s, int modes,
                                    double rtol = 1e-11, double atol = 1e-14);

/// Zero-vibration input shapers for one mode (ω, ζ): impulse times [s] and amplitudes
/// (summing to 1). ZV: 2 impulses; ZVD: 3 (robust to frequency error).
struct InputShaper {
  std::vector<double> times;
  std::vector<double> amplitudes;
};
InputShaper zv_shaper(double omega_rad_s, double zeta = 0.0);
InputShaper zvd_shaper(double omega_rad_s, double zeta = 0.0);

template <>
struct EnumNames<SwitchTimeResult::Status> {
  static constexpr const char* what = "switch-time status";
  static constexpr std::array<std::pair<SwitchTimeResult::Status, const char*>, 2> names{
      {{SwitchTimeResult::Status::Solved, "solved"}, {SwitchTimeResult::Status::NotConverged, "not_converged"}}};
};

template <>
struct EnumNames<SwitchTimeOptions::Refine> {
  static constexpr const char* what = "refinement";
  static constexpr std::array<std::pair<SwitchTimeOptions::Refine, const char*>, 2> names{
      {{SwitchTimeOptions::Refine::Newton, "newton"}, {SwitchTimeOptions::Refine::Slsqp, "slsqp"}}};
};

}  // namespace freeflex
