#pragma once
// The studies a design asks for, each a library call with a typed result a program (the
// command line, Python) can hold: free vibration, maneuver, simulation and suppression.
// They compute and report progress; the command line writes their files and
// summary.json from the results (app/run.hpp).
#include <functional>
#include <limits>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/control/metrics.hpp"
#include "freeflex/control/suppression.hpp"
#include "freeflex/control/switch_time.hpp"
#include "freeflex/enum_names.hpp"
#include "freeflex/io/design.hpp"
#include "freeflex/trajopt/chattering.hpp"
#include "freeflex/trajopt/replay.hpp"
#include "freeflex/trajopt/solve.hpp"

namespace freeflex {

/// The outcome of a study: ok, or failed for the reason in its message (a numerical
/// failure: the command line exits 1).
/// OutOfRange: a simulation left its model's range (a response that grew without bound).
enum class StudyStatus { Ok, Failed, OutOfRange };

template <>
struct EnumNames<StudyStatus> {
  static constexpr const char* what = "study status";
  static constexpr std::array<std::pair<StudyStatus, const char*>, 3> names{
      {{StudyStatus::Ok, "ok"}, {StudyStatus::Failed, "failed"}, {StudyStatus::OutOfRange, "out_of_range"}}};
};

/// Where a study reports while it runs: progress lines on `log` (may be null), and each
/// warning as it happens (every warning is also kept in the result).
struct StudyLog {
  std::ostream* log = nullptr;
  std::function<void(const std::string&)> warn;  ///< optional; must not throw
};

/// Elastic natural frequencies of a design's beam with `noa` functions of its basis and,
/// if asked, an estimate of each one's error from a refined model (docs/theory.md
/// section 4b): finite-element basis, Richardson extrapolation from the same model on
/// twice the elements at the element order's rate (h^4 or h^8); paper's basis, the
/// change to NOA 2 noa (capped at kMaxNoa; at NOA kMaxNoa, the change from NOA kMaxNoa/2),
/// which the error of a Ritz estimate is at least.
struct ModeTable {
  Eigen::VectorXd omega_rad_s, freq_hz, lambda;
  Eigen::VectorXd error_estimate;  ///< relative (omega - omega_exact) / omega; empty unless asked; NaN where none
  std::string error_method;        ///< how error_estimate was found, for reports
};
ModeTable mode_table(const Design& design, int noa, bool estimate_error = false);
/// True when the closed-form free-free beam gives the design's exact frequencies: one
/// uniform span, no hub, no payload (then no error estimate is needed).
bool has_exact_modes(const Design& design);

/// [free_vibration]: frequencies over the NOA sweep, mode shapes against the exact beam.
struct FreeVibrationStudyResult {
  StudyStatus status = StudyStatus::Ok;
  std::string message;
  bool ok() const { return status == StudyStatus::Ok; }
  std::vector<std::string> warnings;

  std::vector<std::string> table_header;  ///< the frequency table (TABLE.csv): one row per (NOA, mode)
  Eigen::MatrixXd table;
  struct Frequencies {
    int noa = 0;
    Eigen::VectorXd lambda, omega_rad_s;  ///< the elastic modes reported at this NOA
    Eigen::VectorXd error_estimate;       ///< relative; empty where the exact beam applies (mode_table)
  };
  std::vector<Frequencies> frequencies;
  std::string error_method;  ///< how error_estimate was found (empty where the exact beam applies)
  struct ModeShape {
    std::string name;
    int noa = 0, mode = 0;
    std::vector<std::string> header;  ///< s_m, x_m, w_freeflex[, w_exact]
    Eigen::MatrixXd data;
    std::optional<double> max_abs_difference;  ///< against the exact free-free mode, where it applies
  };
  std::vector<ModeShape> mode_shapes;
  /// [free_vibration] spin_rates_deg_s: one row per (spin rate, mode): spin_rad_s, mode,
  /// omega2 and omega (NaN where ω² < 0: buckled) with and without stiffening.
  std::vector<std::string> spinning_header;
  Eigen::MatrixXd spinning_table;
};
FreeVibrationStudyResult run_free_vibration_study(const Design& design, const StudyLog& log = {});

/// [maneuver]: the optimal rigid maneuver.
struct ManeuverStudyResult {
  StudyStatus status = StudyStatus::Failed;
  std::string message;
  bool ok() const { return status == StudyStatus::Ok; }
  std::vector<std::string> warnings;

  TrajoptResult trajopt;
  std::optional<FlownManeuver> flown;  ///< when solved: what [simulation] and [controller] fly
  /// When solved: chattering of the controls (a singular arc), with suggested remedies.
  ChatteringReport chattering;
  /// When solved: the commands flown on the zero-order model against the optimizer's
  /// final state (trajopt/replay.hpp).
  std::optional<ReplayCheck> replay;
  /// With an elastic maneuver: the rigid counterpart of its problem (trajopt/problem.hpp)
  /// solved with the same options, for the extra control energy and the suppression
  /// comparison; and, when that solved, what it flies.
  std::optional<TrajoptResult> rigid_optimum;
  std::optional<FlownManeuver> rigid_flown;
};
/// `quiet`: no Ipopt log on the log stream (the design's own `quiet` applies too).
ManeuverStudyResult run_maneuver_study(const Design& design, bool quiet, const StudyLog& log = {});

/// [simulation]: the full model and the perturbation solution, their differences.
struct SimulationStudyResult {
  StudyStatus status = StudyStatus::Ok;
  std::string message;
  bool ok() const { return status == StudyStatus::Ok; }
  std::vector<std::string> warnings;

  double loads_end_s = 0.0;      ///< no load acts after it
  bool about_maneuver = false;   ///< the nominal is the optimized maneuver (else the zero-order simulation)
  /// How the perturbation solution's first-order model was integrated.
  SimulationOptions::FirstOrderSolver first_order_solver = SimulationOptions::FirstOrderSolver::Integrator;
  /// The integrator and the variables it integrated (the full model's are physical under a
  /// prescribed motion, whatever the options say).
  IntegratorOptions::Method method = IntegratorOptions::Method::Adams;
  SimulationOptions::Variables full_variables = SimulationOptions::Variables::Physical;
  SimulationOptions::Variables first_order_variables = SimulationOptions::Variables::Modal;
  double duration_s = 0.0;
  /// A solution, its table (nonlinear.csv or perturbation.csv) and its figures of merit.
  struct Solution {
    SimulationResult run;
    long zero_order_rhs_evaluations = -1, first_order_rhs_evaluations = -1;  ///< perturbation only
    std::vector<std::string> header;
    Eigen::MatrixXd table;         ///< empty when the run failed
    double residual_vibration_energy_J = 0.0;
    /// Full model: drift of energy, linear and angular momentum after the loads end,
    /// relative to their peaks.
    std::optional<Eigen::Vector3d> drifts;
    bool geometric_stiffening = false;  ///< of the model that ran
    /// Where the run stands against its model's range (summary.json "range").
    struct Range {
      double peak_spin_rate_rad_s = 0.0;
      double first_frequency_rad_s = 0.0;  ///< lowest elastic frequency with the reference frame held
      double spin_ratio = 0.0;             ///< peak spin rate / first_frequency
      double peak_deflection_m = 0.0;      ///< largest |u(x)| over the beam and the run
      double length_m = 0.0;
      double deflection_ratio = 0.0;       ///< peak deflection / length
      /// Full model: energy(t_end) − energy(0), the work done on the body over the run,
      /// and the largest |energy change − work| over the run relative to the largest of either.
      std::optional<double> energy_change_J, work_J, energy_balance_error_rel;
    };
    Range range;
    /// Its global integration error, from a second run at tighter tolerances
    /// ([simulation] error_estimate; absent when switched off or the run failed).
    std::optional<GlobalErrorEstimate> error_estimate;
  };
  std::optional<Solution> nonlinear, perturbation;
  /// [simulation] compare_stiffening: the full model with geometric stiffening flipped.
  std::optional<Solution> comparison;
  bool prescribed_motion = false;  ///< [motion]: the reference motion was prescribed
  struct Differences {
    double max_abs_dR_m = 0.0, max_abs_dtheta_rad = 0.0, max_abs_dq = 0.0, max_rigid_difference = 0.0;
  };
  std::optional<Differences> difference_nonlinear_minus_perturbation;  ///< when both completed
  /// Work its integrations were charged (WorkBudget units) of its budget, Design::study_work.
  long long work_units = 0, work_budget_units = 0;
};
SimulationStudyResult run_simulation_study(const Design& design, const ManeuverStudyResult* maneuver = nullptr,
                                           const StudyLog& log = {});

/// [controller] (and [bang_bang]): TV-LQR against the open loop, with metrics per case.
struct SuppressionStudyResult {
  StudyStatus status = StudyStatus::Ok;
  std::string message;
  bool ok() const { return status == StudyStatus::Ok; }
  std::vector<std::string> warnings;

  SuppressionResult chain;  ///< nominal motion, open loop, TV-LQR, closed loops
  /// With a vibration-aware (elastic) maneuver: the same chain about its rigid optimum
  /// (ManeuverStudyResult::rigid_flown), compared beside it.
  std::optional<SuppressionResult> rigid_chain;
  /// A bang-bang rotation leaving the first `modes` elastic modes at rest; without
  /// `modes`, the reason none was designed.
  struct BangBang {
    std::optional<int> modes;
    std::string status;  ///< "ok" or the reason it was not designed / did not converge
    std::optional<SwitchTimeResult> design;
  };
  std::vector<BangBang> bang_bang;
  /// One response compared in comparison.csv: a case (open_loop, tvlqr, bang_bang_kK; with
  /// a vibration-aware maneuver vibration_aware_open_loop, vibration_aware_tvlqr,
  /// rigid_optimum_open_loop, rigid_optimum_tvlqr) on a model (first_order, nonlinear).
  struct Case {
    std::string name, model;
    Eigen::VectorXd t;
    Eigen::MatrixXd z, z_dot, commands;  ///< commands: every element (loads and actuators)
    double saturated_fraction = 0.0;
    ResponseMetrics metrics;
    /// The residual vibration energy's change when the chain (open loop, TV-LQR, closed
    /// loops) runs again at 10x tighter tolerances (twice the Gauss steps): an estimate of
    /// its error [J]; NaN when not estimated (rigid-optimum and bang-bang rows, a spent
    /// work budget).
    double energy_error_estimate_J = std::numeric_limits<double>::quiet_NaN();
  };
  std::vector<Case> cases;
  /// Work its integrations were charged (WorkBudget units) of its budget, Design::study_work.
  long long work_units = 0, work_budget_units = 0;
};
SuppressionStudyResult run_suppression_study(const Design& design, const ManeuverStudyResult* maneuver = nullptr,
                                             const StudyLog& log = {});

}  // namespace freeflex
