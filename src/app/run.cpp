// `freeflex run`: every study of a design in order (maneuver first: simulation and
// controller fly it), their files through a staged output directory, summary.json last.
#include "freeflex/app/run.hpp"

#include <cstdio>
#include <stdexcept>

#include "app/study_files.hpp"
#include "app/sweep_files.hpp"
#include "freeflex/io/output.hpp"
#include "freeflex/version.hpp"
#include "io/staging.hpp"

namespace freeflex {
namespace {

/// Records a study's outcome in the run: a failure adds its reason to the run's message.
template <class R>
void note(RunResult& run, const R& r) {
  if (r.ok()) return;
  // a failure outranks a run out of its range
  run.status = run.status == StudyStatus::Failed || r.status == StudyStatus::Failed ? StudyStatus::Failed : r.status;
  run.message = run.message.empty() ? r.message : run.message + "; " + r.message;
}

/// The studies of the design, their files written through `out` as each ends.
void run_studies(const Design& design, const RunOptions& options, RunResult& run, detail::RunOutput& out) {
  StudyLog study_log;
  study_log.log = options.quiet ? nullptr : options.log;
  study_log.warn = [&out](const std::string& w) { out.warn(w); };
  bool any = false;
  if (design.free_vibration) {
    run.free_vibration = run_free_vibration_study(design, study_log);
    detail::write_free_vibration(design, *run.free_vibration, out);
    note(run, *run.free_vibration);
    any = true;
  }
  const ManeuverStudyResult* maneuver = nullptr;
  if (design.maneuver) {
    run.maneuver = run_maneuver_study(design, options.quiet, study_log);
    detail::write_maneuver(design, *run.maneuver, out);
    note(run, *run.maneuver);
    maneuver = &*run.maneuver;
    any = true;
  }
  const bool flown = !maneuver || maneuver->ok();  // a maneuver that failed leaves nothing to fly
  if (design.simulation && flown) {
    run.simulation = run_simulation_study(design, maneuver, study_log);
    detail::write_simulation(design, *run.simulation, out);
    note(run, *run.simulation);
    any = true;
  }
  if (design.controller && flown) {
    run.suppression = run_suppression_study(design, maneuver, study_log);
    detail::write_suppression(design, *run.suppression, out);
    detail::write_export(design, *run.suppression, out);
    note(run, *run.suppression);
    any = true;
  }
  if (design.lqg && run.suppression) {
    run.lqg = run_lqg_study(design, *run.suppression, maneuver, study_log);
    detail::write_lqg(design, *run.lqg, out);
    note(run, *run.lqg);
  }
  if (design.sweep && run.suppression) {
    SweepExecution ex = options.sweep;
    if (ex.journal.empty() && !options.out_dir.empty()) ex.journal = options.out_dir + "/.freeflex-sweep-journal";
    run.sweep = run_sweep_study(design, *run.suppression, maneuver, ex, study_log);
    detail::write_sweep(design, *run.sweep, out);
    note(run, *run.sweep);
  }
  if (!any) out.warn("the design asks for no study; add [free_vibration] or [simulation] (see README, design keys)");
}

/// summary.json as the last file of `out`, listing the run's files.
void write_summary(const Design& design, RunResult& run, detail::RunOutput& out) {
  run.files = out.files();
  run.files.push_back("summary.json");
  run.warnings = out.warnings();
  const std::string text = summary_json(design, run).dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
  write_file_atomic(out.dir() + "/summary.json", text + "\n");
}

}  // namespace

void validate(const RunOptions& options) {
  if (options.out_dir.find('\0') != std::string::npos)
    throw std::invalid_argument("run options: out_dir contains a NUL character");
  validate(options.plot);
}

RunResult run_design(const Design& design, const RunOptions& options) {
  validate(options);
  std::ostream* warnings = options.quiet ? nullptr : options.errors;
  std::optional<staging::StagedDirectory> dir;  // none: the results only, nothing is written
  if (!options.out_dir.empty()) dir.emplace(options.out_dir);
  detail::RunOutput out(dir ? dir->staging() : "", warnings, options.out_dir, options.plot);
  RunResult run;
  // Messages name DIR, not the staging directory, which is gone by the time they are read.
  const std::string kept = "; '" + options.out_dir + "' keeps the previous run's files";
  try {
    run_studies(design, options, run, out);
  } catch (const IoError& e) {
    throw IoError(out.shown(e.what()) + kept);  // before the commit DIR is untouched
  } catch (const std::invalid_argument&) {
    throw;  // bad input found late: nothing is written (exit 2)
  } catch (const std::exception& e) {
    // A computation that failed in a way no study reports by itself: what was written so
    // far goes out with a summary that says so.
    run.status = StudyStatus::Failed;
    run.message = run.message.empty() ? e.what() : run.message + "; " + e.what();
  }
  if (!dir) {
    run.files = out.files();
    run.warnings = out.warnings();
    return run;
  }
  const std::string failed_before = run.ok() ? "" : "; the run had failed before: " + run.message;
  try {
    write_summary(design, run, out);
  } catch (const IoError& e) {
    throw IoError(out.shown(e.what()) + kept + failed_before);
  }
  try {
    const std::size_t n = dir->commit();
    if (run.sweep && options.sweep.journal.empty()) std::remove((options.out_dir + "/.freeflex-sweep-journal").c_str());
    if (options.log && !options.quiet)
      *options.log << "results: " << options.out_dir << " (" << n << " files, summary.json)\n";
  } catch (const IoError& e) {
    throw IoError(out.shown(e.what()) + failed_before);
  }
  return run;
}

nlohmann::ordered_json summary_json(const Design& design, const RunResult& run) {
  using detail::Json;
  Json summary = Json::object();
  summary["freeflex_version"] = version();
  summary["design"] = design.source;
  summary["title"] = design.title;
  summary["noa"] = design.noa;
  if (design.basis.kind == BasisOptions::Kind::FiniteElement) {  // the paper's basis: as before
    summary["basis"] = to_string(design.basis.kind);
    summary["elements"] = design.basis.finite_element.elements;
    summary["element_order"] = design.basis.finite_element.order;
    // free-free modes (the default): as before
    if (design.basis.finite_element.modes != FiniteElementOptions::Modes::FreeFree)
      summary["fe_modes"] = to_string(design.basis.finite_element.modes);
  }
  summary["status"] = to_string(run.status);
  summary["message"] = run.message;
  Json studies = Json::object();
  if (run.free_vibration) studies["free_vibration"] = detail::to_json(design, *run.free_vibration);
  if (run.maneuver) studies["maneuver"] = detail::to_json(*run.maneuver);
  if (run.simulation) studies["simulation"] = detail::to_json(*run.simulation);
  if (run.suppression) {
    Json s = detail::to_json(design, *run.suppression);
    if (!s.is_null()) studies["suppression"] = s;
  }
  if (run.lqg) studies["lqg"] = detail::to_json(design, *run.lqg);
  if (run.sweep) studies["sweep"] = detail::to_json(design, *run.sweep);
  summary["studies"] = studies;
  Json files = Json::array();
  for (const auto& f : run.files) files.push_back(f);
  summary["files"] = files;
  Json warnings = Json::array();
  for (const auto& w : run.warnings) warnings.push_back(w);
  summary["warnings"] = warnings;
  return summary;
}

namespace detail {

Json json_array(const Eigen::VectorXd& v) {
  Json a = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(v(i));
  return a;
}

}  // namespace detail
}  // namespace freeflex
