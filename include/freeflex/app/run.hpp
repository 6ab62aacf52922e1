#pragma once
// The application layer: what `freeflex run` does with a design. It runs every study the
// design asks for (app/studies.hpp), writes their files through a staging directory
// (io/staging in src/) and summary.json last, and returns the typed results.
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "freeflex/app/progress.hpp"
#include "freeflex/app/studies.hpp"
#include "freeflex/app/sweep.hpp"
#include "freeflex/io/design.hpp"
#include "freeflex/io/plot.hpp"

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
  std::string out_dir;             ///< created if needed; empty: the results only, no file written
  bool quiet = false;              ///< no progress, tables or warnings on the streams below
  std::ostream* log = nullptr;     ///< progress, tables and the closing line; null: silent
  std::ostream* errors = nullptr;  ///< warnings as they happen; null: silent
  PlotOptions plot;                ///< the gnuplot run for figures, and its time limit per figure
  /// [sweep]: threads, MPI share; an empty journal means out_dir/.freeflex-sweep-journal
  /// (kept until the run's files are committed, so that a killed sweep resumes).
  SweepExecution sweep;
};

/// Throws std::invalid_argument for an out_dir no file system accepts or bad plot
/// options; the defaults (no directory: results only) are valid.
void validate(const RunOptions& options);

/// Everything a run did: each study's typed result, the files written (summary.json
/// last) and the warnings.
struct RunResult {
  StudyStatus status = StudyStatus::Ok;
  std::string message;  ///< why the run failed (each failed study's reason, joined by "; ")
  bool ok() const { return status == StudyStatus::Ok; }
  int exit_code() const { return ok() ? kExitOk : kExitNumericalFailure; }

  std::optional<FreeVibrationStudyResult> free_vibration;
  std::optional<ManeuverStudyResult> maneuver;
  std::optional<SimulationStudyResult> simulation;
  std::optional<SuppressionStudyResult> suppression;
  std::optional<LqgStudyResult> lqg;
  std::optional<SweepStudyResult> sweep;
  std::vector<std::string> files;
  std::vector<std::string> warnings;
};

/// Does everything the design asks and writes DIR/summary.json last. Numerical failure
/// is a result (status, message: exit 1). Throws IoError when results cannot be written
/// or another run holds DIR (exit 3) and std::invalid_argument for bad input found late
/// (exit 2; nothing is written).
RunResult run_design(const Design& design, const RunOptions& options);

/// summary.json: the design, the status and message, every study's key figures, the
/// files and warnings.
nlohmann::ordered_json summary_json(const Design& design, const RunResult& result);

}  // namespace freeflex
