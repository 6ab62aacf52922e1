#pragma once
// The application layer: what `freeflex run` and `freeflex modes` do with a design.
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/io/design.hpp"
#include "freeflex/io/output.hpp"
#include "freeflex/io/plot.hpp"
#include "freeflex/trajopt/solve.hpp"

namespace freeflex {

/// Exit codes of the command line (documented in the README).
enum ExitCode : int {
  kExitOk = 0,
  kExitNumericalFailure = 1,  ///< a solver or integrator did not succeed; reason in the output
  kExitBadInput = 2,          ///< bad design, option or file name; nothing was written
  kExitIoFailure = 3,         ///< results could not be written
};

/// Where a run writes and how much it says.
struct RunOptions {
  std::string out_dir;
  bool quiet = false;
  std::ostream* log = nullptr;  ///< progress and tables; null: silent
};

/// Collects the files of one run and the figures that could not be drawn.
class RunOutput {
 public:
  /// Files go into `dir`; messages name `shown_dir` (where they end up) if it is given.
  RunOutput(std::string dir, std::ostream* log, std::string shown_dir = {})
      : dir_(std::move(dir)), shown_dir_(shown_dir.empty() ? dir_ : std::move(shown_dir)), log_(log) {}
  void write(const std::string& name, const std::string& content);
  void csv(const std::string& name, const std::vector<std::string>& header, const Eigen::MatrixXd& data);
  /// Renders a plot (unless plots are off); a failure becomes a warning, not an error.
  void plot(const PlotSpec& spec, bool enabled);
  void warn(const std::string& message);
  std::ostream* log() const { return log_; }
  const std::string& dir() const { return dir_; }
  const std::vector<std::string>& files() const { return files_; }
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  std::string shown(std::string text) const;
  /// Writes `name` in dir() through `writer` and counts it among the run's files.
  void stream(const std::string& name, const std::function<void(std::ostream&)>& writer);

  std::string dir_, shown_dir_;
  std::ostream* log_;
  std::vector<std::string> files_, warnings_;
};

/// How far a long phase has got, on the log: a line at most every `every_s` seconds of
/// wall time ("  4.2 of 20 s (21%) after 6 s"), none if the phase ends sooner.
class ProgressReport {
 public:
  /// `every_s` = 0: a line for every call (for tests).
  ProgressReport(std::ostream* log, double total_s, double every_s = 2.0);
  /// The phase has covered `t` seconds of simulated time out of `total_s`.
  void update(double t);
  /// For phases without a known end: "  <what> after 6 s", at the same pace as update().
  void note(const std::string& what);
  /// update() as a callback (IntegratorOptions::progress); this object must outlive it.
  std::function<void(double)> callback();
  /// What to print before the phase's closing words: a new indented line if progress
  /// lines were printed, nothing otherwise.
  const char* resume() const { return printed_ ? "  " : ""; }

 private:
  void schedule(double now);  ///< sets when the next line is due

  std::ostream* log_;
  double total_s_, every_s_;
  double start_, next_;
  bool printed_ = false;
};

/// Elastic natural frequencies of a design's beam with `noa` functions.
struct ModeTable {
  Eigen::VectorXd omega_rad_s, freq_hz, lambda;
};
ModeTable mode_table(const Design& design, int noa);

/// Does everything the design asks and writes DIR/summary.json last. Returns an
/// ExitCode; throws std::runtime_error only when a file cannot be written.
int run_design(const Design& design, const RunOptions& options);

/// The [free_vibration] study; adds its results to `summary`.
void run_free_vibration(const Design& design, RunOutput& out, Json& summary);
/// What [maneuver] hands to [simulation]: the optimized motion and its commands.
struct ManeuverOutcome {
  int code = kExitOk;
  std::shared_ptr<const CollocationTrajectory> trajectory;  ///< null if it failed
  std::vector<int> actuators;                               ///< element index of each command
  double duration_s = 0.0;
  /// Adds the optimized commands to their actuators in `ex` (nothing after the maneuver).
  void drive(Excitation& ex) const;
  /// The optimized motion, continued at rest (its final rates) after it ends.
  std::shared_ptr<const RigidTrajectory> nominal() const;
};
/// The [maneuver] study.
ManeuverOutcome run_maneuver(const Design& design, RunOutput& out, Json& summary, bool quiet);
/// The [controller] study: TV-LQR against the open loop, comparison.csv; returns an ExitCode.
int run_suppression(const Design& design, RunOutput& out, Json& summary, const ManeuverOutcome* maneuver = nullptr);
/// The [simulation] study, about the optimized maneuver if one is given; returns an ExitCode.
int run_simulation(const Design& design, RunOutput& out, Json& summary, const ManeuverOutcome* maneuver = nullptr);

}  // namespace freeflex
