#pragma once
// [lqg] and [sweep]: the [controller]'s TV-LQR flown as a sampled-data controller on the
// full nonlinear model, with the exact state or with a Kalman filter (LQG), on the
// nominal plant and on every sample of an uncertainty sweep (control/lqg.hpp).
//
// A sweep's results do not depend on how it is run: sample i draws its parameters and
// its noise from (seed, i) alone, samples are independent, and statistics are taken in
// sample order, so any number of threads (std::thread) or MPI ranks gives the same bytes.
// A journal beside the results keeps every finished sample (exact, hexadecimal floats);
// a run of the same design that finds it skips those samples.
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/app/studies.hpp"
#include "freeflex/control/lqg.hpp"
#include "freeflex/control/metrics.hpp"

namespace freeflex {

/// [lqg]: full-state TV-LQR and LQG, both sampled, on the nominal full model.
struct LqgStudyResult {
  StudyStatus status = StudyStatus::Ok;
  std::string message;
  bool ok() const { return status == StudyStatus::Ok; }
  std::vector<std::string> warnings;

  KalmanResult filter;
  TvlqrResult digital_law;  ///< solve_discrete_tvlqr at the sample rate
  struct Case {
    /// tvlqr_sampled: the continuous law's gains at the samples (exact state);
    /// digital_tvlqr: the digital law (exact state); lqg: the digital law on the filter's estimate
    std::string name;
    SampledLoopResult run;
    ResponseMetrics metrics;
    /// |change of residual_vibration_energy_J| when the flight is flown again at 10x
    /// tighter tolerances (LqgStudy::error_estimate); NaN when not estimated.
    double energy_error_estimate_J = std::numeric_limits<double>::quiet_NaN();
  };
  std::vector<Case> cases;
  double open_loop_energy_J = 0.0;    ///< the [controller]'s open loop on the full model
  double continuous_energy_J = 0.0;   ///< the [controller]'s continuous TV-LQR on the full model
  /// The filter's 1σ of each elastic coordinate q_i at the end (square roots of P⁺'s diagonal).
  Eigen::VectorXd final_elastic_std;
  /// Work its integrations were charged (WorkBudget units) of its budget, Design::study_work.
  long long work_units = 0, work_budget_units = 0;
};
LqgStudyResult run_lqg_study(const Design& design, const SuppressionStudyResult& suppression,
                             const ManeuverStudyResult* maneuver = nullptr, const StudyLog& log = {});

/// One sample of a sweep.
struct SweepSample {
  long index = -1;              ///< -1: not run
  std::vector<double> values;   ///< one per SweepStudy::parameters, in their order
  bool ok = false;              ///< the flight completed
  ResponseMetrics metrics;
  double wall_time_s = 0.0;
};

/// How a sweep runs: threads, this process's share of the samples (MPI ranks), and the
/// journal of finished samples.
struct SweepExecution {
  int threads = 0;  ///< 0: every core (std::thread::hardware_concurrency)
  int rank = 0;     ///< this process runs the samples i with i % ranks == rank
  int ranks = 1;
  /// After the local share: completes `samples` with the other ranks' (MPI); must leave
  /// every entry run. Needed when ranks > 1.
  std::function<void(std::vector<SweepSample>& samples)> gather;
  std::string journal;  ///< file of finished samples (created, appended, read back); empty: none
};
/// Throws std::invalid_argument for threads < 0, rank outside [0, ranks), or ranks > 1
/// without gather.
void validate(const SweepExecution& execution);

struct SweepStudyResult {
  StudyStatus status = StudyStatus::Ok;
  std::string message;
  bool ok() const { return status == StudyStatus::Ok; }
  std::vector<std::string> warnings;

  std::vector<std::string> parameter_names;
  std::vector<SweepSample> samples;  ///< in sample order
  long completed = 0, failed = 0;
  long resumed = 0;  ///< read from the journal instead of flown
  /// Residual vibration energy of the completed samples [J].
  double mean_J = 0.0, p05_J = 0.0, p50_J = 0.0, p95_J = 0.0, worst_J = 0.0;
  double fraction_meeting = 0.0;  ///< of all samples (a failed one does not meet it)
  /// What the sampling alone leaves uncertain, 95% confidence intervals (as for
  /// independent draws; conservative with grid parameters): Wilson's score interval of
  /// fraction_meeting, and the distribution-free interval of p95_J from the order
  /// statistics (NaN when fewer than n q (1 − q) >= 5 allows: 106 completed samples).
  double fraction_meeting_low = 0.0, fraction_meeting_high = 1.0;
  double p95_low_J = 0.0, p95_high_J = 0.0;
  /// The integration's share of the uncertainty (SweepStudy::error_estimate): the median,
  /// 95th-percentile, worst and nearest-the-requirement (in log E) completed samples flown
  /// again at 10x tighter tolerances, in that order (one entry per distinct sample),
  /// charged to the study's budget (the filter's and digital law's).
  struct ErrorCheck {
    std::string role;         ///< "median", "p95", "worst", "nearest_requirement"
    long index = -1;
    double energy_J = 0.0;    ///< residual vibration energy as the sweep flew it
    double tight_energy_J = std::numeric_limits<double>::quiet_NaN();  ///< NaN: the tighter flight failed
    std::string message;      ///< why the tighter flight failed
  };
  std::vector<ErrorCheck> error_checks;
  /// Largest |tight − flown| / flown over error_checks (NaN when none completed).
  double max_relative_error_estimate = std::numeric_limits<double>::quiet_NaN();
  int threads = 1, ranks = 1;
  double wall_time_s = 0.0;         ///< flying this process's samples
  double time_per_sample_s = 0.0;   ///< wall time / samples flown here (threads and ranks included)
  double cpu_time_per_sample_s = 0.0;  ///< mean time of one sample on one core
  /// Work (WorkBudget units) of the filter and the digital law, and of the samples flown
  /// here; each sample's share of Design::sweep_work (at most Design::study_work).
  long long setup_work_units = 0, sample_work_units = 0, work_share_per_sample = 0;
};
SweepStudyResult run_sweep_study(const Design& design, const SuppressionStudyResult& suppression,
                                 const ManeuverStudyResult* maneuver = nullptr, const SweepExecution& execution = {},
                                 const StudyLog& log = {});

/// The parameter values of sample `index` (one per parameter, in order): grid
/// parameters from index / samples, the others drawn from (seed, index).
std::vector<double> sweep_sample_values(const SweepStudy& sweep, long index);

/// Wilson's score interval [low, high] of a proportion: `successes` of `n` independent
/// trials, z the normal quantile (1.96: 95%). n = 0 gives [0, 1].
std::pair<double, double> wilson_interval(long successes, long n, double z = 1.959963984540054);

/// Distribution-free interval of the q-quantile of the population a sorted sample came
/// from: the order statistics at ranks n q ∓ z sqrt(n q (1 − q)) (the normal approximation
/// to the binomial rank); NaN, NaN when n q (1 − q) < 5.
std::pair<double, double> quantile_interval(const std::vector<double>& sorted, double q,
                                            double z = 1.959963984540054);

}  // namespace freeflex
