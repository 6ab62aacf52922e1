#pragma once
// Design files: a TOML scenario loaded into a validated struct (README, design keys).
// Keys carry their unit (length_m, bending_stiffness_Nm2); angles are degrees in files
// and radians inside. A file is validated whole before any work: every problem is
// collected, each naming the key, the line, what was found and what is allowed, and
// unknown keys are errors. A key left out takes the default of the struct it sets (the
// default-constructed study or library Options below).
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "freeflex/control/lqg.hpp"
#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/tvlqr.hpp"
#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/model/beam.hpp"
#include "freeflex/model/loads.hpp"
#include "freeflex/sim/prescribed.hpp"
#include "freeflex/sim/simulate.hpp"
#include "freeflex/trajopt/problem.hpp"

namespace freeflex {

/// Limits on what a design may ask for (README "design keys", the "(limits)" row). They
/// are generous: they catch typos and absurd magnitudes before any work, and bound every
/// count and size a design implies (rows, files, text, sweep entries, mode shapes, the
/// work of each study) so that no run can exhaust memory or run unbounded.
namespace design_limits {
inline constexpr std::size_t kMaxFileBytes = 1 << 20;     ///< a design file: 1 MiB
inline constexpr std::size_t kMaxTitleBytes = 256;        ///< the title (it reaches every figure)
inline constexpr double kMaxTime_s = 1e6;                 ///< any time, duration or horizon
inline constexpr double kMinDuration_s = 1e-6;            ///< any duration or horizon
inline constexpr double kMaxOutputRows = 200000;          ///< rows of one output series, TV-LQR grid points
inline constexpr double kMaxTrajectorySamples = 1000000;  ///< samples of the zero-order motion
inline constexpr int kMaxForceElements = 64;              ///< [[load]] and [[actuator]] tables together
/// [[beam.segment]] tables, and [[beam.point_mass]] tables (each count): building a body
/// costs about p² x (1 + noa / 10) µs for p of them together (0.56 s at 200 and noa 100),
/// and every study builds one (a [sweep], one per sample).
inline constexpr int kMaxBeamPieces = 100;
inline constexpr int kMaxSensors = 64;                    ///< [[sensor]] tables (rows of C)
inline constexpr std::size_t kMaxProfileTimes = 10000;    ///< times_s entries of all load profiles and motion tables
inline constexpr int kMaxNoaSweep = 100;                  ///< entries of free_vibration.noa_sweep
inline constexpr int kMaxModeShapes = 20;                 ///< [[free_vibration.mode_shape]] tables
inline constexpr int kMaxModeShapePoints = 100000;        ///< points of one mode shape
inline constexpr double kMaxModeShapeRows = 200000;       ///< points of all mode shapes together
/// [free_vibration] on the finite-element basis: element-modes (elements x (modes + 2))
/// of every element model it solves, its NOA sweep with the error estimates' second
/// models, its mode shapes and spin rates; measured up to 4.2e-5 s of CPU each (2000
/// quintic elements, 100 modes: 8.4 s), so about 2 min at most.
inline constexpr double kMaxBasisWork = 3e6;
inline constexpr int kMaxIntervals = 5000;                ///< collocation intervals (trajopt's max_intervals)
inline constexpr int kMaxMeshRefinements = 20;            ///< mesh-refinement rounds
inline constexpr long kMaxIterations = 1000000;           ///< Ipopt max_iter (either key)
/// Ipopt iterations x NLP unknowns, summed over the mesh-refinement rounds (each round's
/// mesh at most doubles, up to kMaxIntervals): the optimizer's work, 3.2 to 4 µs of CPU
/// per unit (measured: 20 and 24 iterations on 5000 intervals, 70 007 unknowns: 4.5 s and
/// 6.7 s), so about 3 min at the bound. An elastic maneuver's derivatives count as
/// max(0, s³/100 - 4 s) more unknowns at each point of s unknowns (fitted: like the rigid
/// problem's at s = 16, 8 to 13 ms a point and iteration at s = 71, 0.1 to 0.24 s at
/// s = 211), and the rigid counterpart solved after it adds its own.
inline constexpr double kMaxIpoptWork = 4.5e7;
/// An elastic maneuver's NLP: collocation points x (unknowns per point)², bounding the
/// memory of Ipopt's matrices (about 20 doubles per point and unknown², measured 0.36 GB
/// at 401 points of 71 unknowns), so about 400 MB.
inline constexpr double kMaxElasticNlpSize = 2.5e6;
/// NLP unknowns Ipopt's derivative checker may test: its work grows like n³ for the
/// first-order test and faster (about n^3.8) for the second-order ones. At these sizes
/// each takes about 15 s of CPU (docs: README, the "(limits)" row).
inline constexpr double kMaxDerivativeTestUnknowns = 2000;
inline constexpr double kMaxSecondOrderTestUnknowns = 400;
/// Doubles of the matrices a study keeps along time (400 MB): the TV-LQR's gains (grid
/// points x actuators x 2 (3 + noa)), the [lqg] filter and digital law, [export]'s model.
inline constexpr double kMaxGainStorage = 5e7;
/// Work of the Gauss closed loop ([controller] closed_loop_first_order_method = "gauss"):
/// Gauss steps x (5 n)³, n = 2 (3 + model.noa), one dense LU of the 5-stage system per
/// step, the steps counted as closed_loop_gauss_steps per interval of the gain grid and
/// of the output times: about 3 min (designs/suppress_slew.toml with 8 steps: 8 000
/// steps at NOA 6, 5.9e9, 1.7 s).
inline constexpr double kMaxGaussWork = 6e11;
/// [export] "poles": model grid points x n³ for n = 2 (3 + noa) states (two eigenvalue
/// problems of n x n at each point, measured 3 to 6 ns per n³ each: about 30 s at most).
inline constexpr double kMaxPolesWork = 2.5e9;
/// Work of one study ([simulation], [controller] with its bang-bang rotations, [lqg]):
/// the CVODES steps of all its integrations, each weighted by what it integrates
/// (step_work: max(N², 400) for a model of N = 3 + noa coordinates, three times that with
/// BDF; riccati_step_work: n³ for the TV-LQR's n = 2N states). Measured 1.4 to 6 ns of
/// CPU per unit, so at most about 2 min; spending it ends the study as a numerical failure.
inline constexpr long long kMaxStudyWork = 20000000000LL;
/// Work of a [sweep]'s samples together (the same units; about 100 min of CPU at the
/// worst, shared out over threads and ranks): each sample may spend an equal share, at
/// most kMaxStudyWork, and the design is refused when the samples' least work (one step
/// per sample interval) exceeds it.
inline constexpr long long kMaxSweepWork = 1000000000000LL;
inline constexpr double kMinLength_m = 1e-3, kMaxLength_m = 1e4;
inline constexpr double kMinMass_kg = 1e-6, kMaxMass_kg = 1e9;
inline constexpr double kMinMassPerLength_kg_m = 1e-6, kMaxMassPerLength_kg_m = 1e6;
inline constexpr double kMinBendingStiffness_Nm2 = 1e-6, kMaxBendingStiffness_Nm2 = 1e12;
inline constexpr double kMaxRotaryInertia_kgm2 = 1e12;
inline constexpr double kEndMargin = 1e-3;                             ///< o at least this fraction of L from an end
inline constexpr double kMaxCommand = 1e12;                            ///< |load value|, actuator limit (N or N m)
inline constexpr double kMinDirection = 1e-6, kMaxDirection = 1e6;     ///< |direction| of a force element
inline constexpr double kMaxWeight = 1e12;                             ///< objective and LQR weights
inline constexpr double kMinInputWeight = 1e-12;                       ///< LQR input weights
inline constexpr double kMaxInputWeightSpread = 1e12;  ///< largest / smallest input weight (the LQR needs < 1e14)
inline constexpr double kMaxPosition_m = 1e6, kMaxVelocity_m_s = 1e6;  ///< maneuver states
inline constexpr double kMaxAngle_deg = 1e6, kMaxRate_deg_s = 1e6;
}  // namespace design_limits

/// All problems found in one design file; what() lists them, one per line.
class DesignError : public std::runtime_error {
 public:
  explicit DesignError(std::vector<std::string> problems);
  const std::vector<std::string>& problems() const { return problems_; }

 private:
  std::vector<std::string> problems_;
};

/// A mode shape to export: elastic mode `mode` (1-based) computed with `noa` functions,
/// drawn against the exact free-free mode of the same number.
struct ModeShapeRequest {
  std::string name;
  int noa = 6;
  int mode = 1;
  int points = 201;
};

/// [free_vibration]: frequencies for a sweep of NOA, optional mode shapes.
struct FreeVibrationStudy {
  std::vector<int> noa_sweep;        ///< empty: the model's noa only
  int modes = 4;                     ///< elastic modes reported per NOA
  bool paper_table = false;          ///< add the paper's printed Table 1 beside ours
  std::string table_name = "frequencies";
  std::vector<ModeShapeRequest> mode_shapes;
  /// Steady spin rates [rad/s] (read in deg/s): elastic frequencies with the reference frame
  /// held spinning, with and without geometric stiffening, into spinning_table_name.csv.
  std::vector<double> spin_rates;
  std::string spinning_table_name = "spinning_frequencies";
};

/// A load: a force element driven by a time profile ([[load]]).
struct LoadSpec {
  ForceElement element;
  TimeProfile profile;
};

/// An actuator: a force element driven by a controller ([[actuator]]).
struct ActuatorSpec {
  ForceElement element;
  double limit = 0.0;  ///< |u| <= limit (N or N m); 0: unbounded
};

/// [simulation]: forced response with the full and the perturbation models.
struct SimulationStudy {
  SimulationOptions options;
  bool nonlinear = true;
  bool perturbation = true;
  /// Run every simulation a second time at tolerances 100 times tighter and report the
  /// difference as the estimate of its global error (GlobalErrorEstimate).
  bool error_estimate = true;
  std::string rigid_figure = "rigid_motion";
  std::string elastic_figure = "generalized_displacements";
  /// Run the full model a second time with [model] geometric_stiffening flipped
  /// (nonlinear_stiffening_off.csv or _on.csv) and overlay the tip deflections of every
  /// run in `tip_figure`.
  bool compare_stiffening = false;
  std::string tip_figure = "tip_deflection";
};

/// [motion]: the reference frame's motion prescribed instead of driven by loads
/// (docs/theory.md section 14, eq. 14.10): θ(t) and the hub centre's x(t), y(t), each at rest,
/// a spin-up ramp or a table with rates and accelerations; o at hub_radius_m from the
/// centre along the body x axis. With o at an end of the beam: a clamped appendage.
struct MotionSpec {
  MotionProfile x, y, theta;
  double hub_radius_m = 0.0;
  PrescribedMotion trajectory() const { return PrescribedMotion(x, y, theta, hub_radius_m); }
};

/// [maneuver]: an optimal rigid maneuver with the design's actuators.
struct ManeuverStudy {
  ManeuverProblem problem;                  ///< actuator indices into Design::force_elements()
  TrajoptOptions options;
  std::vector<std::string> actuator_names;  ///< in the order of problem.actuators
  bool quiet = false;                       ///< no Ipopt log as progress (options.verbose follows the run)
};

/// [controller]: feedback designed on the first-order model about the nominal motion.
struct ControllerStudy {
  std::vector<std::string> actuator_names;
  std::vector<int> actuators;       ///< element indices, in the order of actuator_names
  Eigen::VectorXd limits;           ///< |u| bound per feedback actuator (infinity: none)
  double horizon_s = 3.0;           ///< TV-LQR over [0, horizon_s]
  double weight_elastic = 1.0;      ///< on blockdiag(K, M) of (q, q')
  double weight_rigid_position = 1.0;
  double weight_rigid_rate = 1.0;
  Eigen::VectorXd input_weights;    ///< R diagonal, one per actuator (> 0)
  double grid_step_s = TvlqrOptions{}.grid_step_s;  ///< spacing of the stored gains
  double simulate_until_s = 0.0;    ///< end of the comparison runs (0: the horizon)
  std::string figure = "comparison";
  /// CVODES tolerances of the closed-loop runs (defaults: closed_loop_integrator()).
  double closed_loop_rtol = closed_loop_integrator().rtol;
  double closed_loop_atol = closed_loop_integrator().atol;
  /// How the first-order closed loop is integrated (ClosedLoopOptions).
  ClosedLoopMethod closed_loop_first_order_method = ClosedLoopMethod::Cvodes;
  int closed_loop_gauss_steps = ClosedLoopOptions{}.gauss_steps;
  /// Run the chain again at 10x tighter tolerances (twice the Gauss steps) and report each
  /// case's energy change as its error estimate (SuppressionStudyResult::Case).
  bool error_estimate = true;
  /// How the TV-LQR's Riccati equation is integrated (TvlqrOptions::method).
  TvlqrOptions::Method tvlqr_method = TvlqrOptions::Method::Auto;
};

/// [export]: what the controller study leaves for other tools (README, outputs): files
/// NAME.mat (MATLAB level 5, readable by scipy.io.loadmat and Octave) and/or NAME_*.csv.
struct ExportRequest {
  std::string name = "controller";  ///< stem of the exported files
  bool csv = true, mat = true;      ///< formats
  /// What: the TV-LQR gains and feedforward, the nominal x0(t), u0(t), the first-order
  /// model A(t), B(t), g(t), the frozen-time poles of A and A - BK, every comparison
  /// case's histories.
  bool gains = true, nominal = true, model = true, poles = true, histories = true;
  double model_step_s = 0.0;  ///< spacing of the model grid [s] (0: the TV-LQR gain grid's)
};

/// [bang_bang]: rest-to-rest bang-bang rotations by one torque actuator at o whose switch
/// times leave the first k elastic modes at rest (compared beside the controller).
struct BangBangStudy {
  std::string actuator_name;
  int actuator = -1;          ///< element index
  std::vector<int> modes = {1, 2};  ///< distinct k values, each in [0, 4] and at most the modes the actuator excites
};

/// [lqg]: the [controller]'s TV-LQR flown as a sampled-data (digital) controller on the
/// full model, with the exact state and with the Kalman filter of the [[sensor]]s (LQG).
struct LqgStudy {
  double sample_rate_hz = 1000.0;        ///< sensors and controller
  Eigen::VectorXd process_noise_density; ///< per controller actuator [N/√Hz or N m/√Hz]
  double initial_std = 1e-3;             ///< the filter's P0 = initial_std² I
  PlantOptions plant;                    ///< actuator gain, lag, delay, noise seed
  bool delay_known = false;              ///< the controller predicts over the delay
  /// Fly each case again at 10x tighter integration tolerances and report its change of
  /// residual vibration energy (LqgStudyResult::Case::energy_error_estimate_J).
  bool error_estimate = true;
  std::string table = "lqg";             ///< TABLE.csv: one row per case
  std::string figure = "lqg";
};

/// One uncertain parameter of a [sweep] ([sweep.NAME]).
struct SweepParameter {
  enum class Name { BendingStiffnessScale, MassScale, DampingRatio, ActuatorGain, DelayS, LagS };
  enum class Kind { Uniform, Normal, Grid };
  Name name = Name::BendingStiffnessScale;
  Kind kind = Kind::Uniform;
  double a = 0.0, b = 0.0;  ///< uniform and grid: [min, max]; normal: mean, std
  int points = 1;           ///< grid
};

/// [sweep]: the [controller]'s TV-LQR (or LQG with [lqg]) designed once on the nominal
/// model and flown on every sample of the uncertain parameters with the full model.
struct SweepStudy {
  int samples = 100;          ///< per grid point
  std::uint64_t seed = 1;     ///< parameters and noise of sample i come from (seed, i)
  SampledLoopOptions::Feedback feedback = SampledLoopOptions::Feedback::FullState;
  double sample_rate_hz = 1000.0;
  double requirement_energy_J = 0.0;  ///< a sample meets it when its residual vibration energy is <= this
  /// Fly the median, the 95th percentile's, the worst and the nearest-the-requirement
  /// completed samples again at 10x tighter integration tolerances
  /// (SweepStudyResult::error_checks).
  bool error_estimate = true;
  std::vector<SweepParameter> parameters;
  std::string table = "sweep";             ///< TABLE.csv: one row per sample
  std::string figure = "sweep_histogram";  ///< histogram of log10 residual energy
  /// Total samples: samples times the product of the grid sizes.
  long total_samples() const;
};

struct Design {
  std::string source;  ///< file name, for messages
  std::uint64_t digest = 0;  ///< FNV-1a of the file's text (a resumed sweep checks it)
  std::string title;
  BeamProperties beam;
  int noa = 6;         ///< [model] number of shape functions (elastic coordinates)
  BasisOptions basis;  ///< [model] which basis: the paper's (default) or finite-element modes
  /// [model] geometric_stiffening: keep the foreshortening of the bent beam (docs/theory.md
  /// section 14). On unless a design says otherwise: the paper's model is linear-elastic
  /// in the floating frame and fails on spinning structures (Kane, Ryan and Banerjee).
  bool geometric_stiffening = true;
  std::optional<MotionSpec> motion;  ///< [motion]: prescribed reference motion
  bool plots = true;   ///< [output] write PNG figures with gnuplot
  std::vector<LoadSpec> loads;
  std::vector<ActuatorSpec> actuators;
  std::vector<double> damping_ratios;  ///< [damping] ratios, per elastic mode
  std::optional<FreeVibrationStudy> free_vibration;
  std::optional<SimulationStudy> simulation;
  std::optional<ManeuverStudy> maneuver;
  std::optional<ControllerStudy> controller;
  std::optional<BangBangStudy> bang_bang;
  std::vector<Sensor> sensors;  ///< [[sensor]]
  std::optional<LqgStudy> lqg;
  std::optional<SweepStudy> sweep;
  std::optional<ExportRequest> exports;  ///< [export] (needs [controller])
  /// The work budget of each study and of a sweep's samples together (WorkBudget; README,
  /// the "(limits)" row). Not design keys: a program may lower them (the tests do).
  long long study_work = design_limits::kMaxStudyWork;
  long long sweep_work = design_limits::kMaxSweepWork;

  /// Force elements: loads first, then actuators (the order of the commands vector).
  std::vector<ForceElement> force_elements() const;
  /// The loads' profiles in that order (actuators have none).
  Excitation excitation() const;
  /// The discretized body every model of the design is built on: the beam on the design's
  /// basis with `noa` functions, its force elements and damping.
  FlexibleBody body() const;
};

/// Work units (WorkBudget's) of building the body a [sweep] sample flies, on the paper's
/// basis: N³ (15 + p) + 400 (1 + noa / 10) p² for N = 3 + noa and p segments and point
/// masses together (measured 0.05 s at noa 100 and p = 1, 0.56 s at p = 200: 4 ns a unit
/// or less); on the finite-element basis 12 000 elements (noa + 2) more for its element
/// model. Each sample is charged it.
long long body_build_work(const Design& design);

/// Reads and validates a design file. Throws DesignError (bad content, unreadable file,
/// not a regular file, larger than design_limits::kMaxFileBytes).
Design load_design(const std::string& path);
/// Same, from text; `source` names it in messages.
Design parse_design(const std::string& text, const std::string& source);

template <>
struct EnumNames<SweepParameter::Name> {
  static constexpr const char* what = "sweep parameter";
  static constexpr std::array<std::pair<SweepParameter::Name, const char*>, 6> names{
      {{SweepParameter::Name::BendingStiffnessScale, "bending_stiffness_scale"},
       {SweepParameter::Name::MassScale, "mass_scale"},
       {SweepParameter::Name::DampingRatio, "damping_ratio"},
       {SweepParameter::Name::ActuatorGain, "actuator_gain"},
       {SweepParameter::Name::DelayS, "delay_s"},
       {SweepParameter::Name::LagS, "lag_s"}}};
};

template <>
struct EnumNames<SweepParameter::Kind> {
  static constexpr const char* what = "distribution";
  static constexpr std::array<std::pair<SweepParameter::Kind, const char*>, 3> names{
      {{SweepParameter::Kind::Uniform, "uniform"},
       {SweepParameter::Kind::Normal, "normal"},
       {SweepParameter::Kind::Grid, "grid"}}};
};

}  // namespace freeflex
