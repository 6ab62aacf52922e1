#include "freeflex/app/run.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>
#include <stdexcept>

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include "freeflex/io/plot.hpp"
#include "freeflex/version.hpp"
#include "util/format.hpp"

namespace freeflex {

void RunOutput::write(const std::string& name, const std::string& content) {
  write_file_atomic(dir_ + "/" + name, content);
  files_.push_back(name);
}

void RunOutput::csv(const std::string& name, const std::vector<std::string>& header, const Eigen::MatrixXd& data) {
  write(name, csv_text(header, data));
}

void RunOutput::adopt(const std::string& name) {
  struct stat st {};
  if (::stat((dir_ + "/" + name).c_str(), &st) == 0 && S_ISREG(st.st_mode) &&
      std::find(files_.begin(), files_.end(), name) == files_.end())
    files_.push_back(name);
}

void RunOutput::plot(const PlotSpec& spec, bool enabled) {
  if (!enabled) return;
  const std::string why = render_plot(spec, dir_);
  files_.push_back(spec.name + ".gp");
  if (why.empty()) files_.push_back(spec.name + ".png");
  else warn("figure " + spec.name + ".png not drawn: " + why);
}

void RunOutput::warn(const std::string& message) {
  warnings_.push_back(message);
  if (log_) *log_ << "warning: " << message << '\n';
}

namespace {
double wall_s() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}
}  // namespace

ProgressReport::ProgressReport(std::ostream* log, double total_s, double every_s)
    : log_(log), total_s_(total_s), every_s_(every_s), start_(wall_s()), next_(start_ + every_s) {}

void ProgressReport::update(double t) {
  if (!log_) return;
  const double now = wall_s();
  if (now < next_) return;
  next_ = now + std::max(every_s_, 0.25 * (now - start_));  // sparser as the phase goes on
  const double pct = total_s_ > 0.0 ? 100.0 * t / total_s_ : 100.0;
  *log_ << (printed_ ? "" : "\n") << "  " << util::format_number(t, 4) << " of " << util::format_number(total_s_, 6)
        << " s (" << static_cast<int>(pct) << "%) after " << static_cast<int>(now - start_) << " s\n"
        << std::flush;
  printed_ = true;
}

void ProgressReport::note(const std::string& what) {
  if (!log_) return;
  const double now = wall_s();
  if (now < next_) return;
  next_ = now + std::max(every_s_, 0.25 * (now - start_));  // sparser as the phase goes on
  *log_ << (printed_ ? "" : "\n") << "  " << what << " after " << static_cast<int>(now - start_) << " s\n"
        << std::flush;
  printed_ = true;
}

std::function<void(double)> ProgressReport::callback() {
  return [this](double t) { update(t); };
}

namespace {

/// Creates DIR (and missing parents). Throws IoError with the reason.
void make_dirs(const std::string& dir) {
  std::string partial;
  std::size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    partial = dir.substr(0, pos);
    if (partial.empty()) continue;
    if (::mkdir(partial.c_str(), 0755) != 0 && errno != EEXIST)
      throw IoError("cannot create output directory '" + partial + "': " + std::strerror(errno));
  }
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw IoError("output path '" + dir + "' exists and is not a directory");
}

/// Names of the regular files in `dir` (not recursive); empty if it cannot be read.
std::vector<std::string> list_files(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir.c_str());
  if (!d) return names;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name == "." || name == "..") continue;
    struct stat st {};
    if (::stat((dir + "/" + name).c_str(), &st) == 0 && S_ISREG(st.st_mode)) names.push_back(name);
  }
  ::closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

/// Removes a flat directory of files (a staging directory); best effort.
void remove_flat_dir(const std::string& dir) {
  for (const auto& f : list_files(dir)) std::remove((dir + "/" + f).c_str());
  ::rmdir(dir.c_str());
}

// A run writes into DIR/.freeflex-staging-<pid> and moves its files into DIR only when it
// has finished (successfully or with a reported numerical failure), so DIR never holds a
// mixture of two runs: an interrupted run leaves the previous results as they were. The
// manifest lists the files the last finished run left in DIR; the next one removes them
// first, so no stale result outlives the run that replaced it. summary.json goes last.
const char* const kManifest = ".freeflex-files";
const char* const kStagingPrefix = ".freeflex-staging-";

std::vector<std::string> read_manifest(const std::string& dir) {
  std::vector<std::string> names;
  std::ifstream in(dir + "/" + kManifest);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty() && line.find('/') == std::string::npos && line != "." && line != "..") names.push_back(line);
  return names;
}

/// Staging directories left by runs that were killed (any process id).
void remove_stale_staging(const std::string& dir) {
  DIR* d = ::opendir(dir.c_str());
  if (!d) return;
  std::vector<std::string> stale;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.rfind(kStagingPrefix, 0) == 0) stale.push_back(dir + "/" + name);
  }
  ::closedir(d);
  for (const auto& s : stale) remove_flat_dir(s);
}

/// Moves every file of `staging` into `dir`, replacing the previous run's files; returns
/// how many it moved.
std::size_t commit(const std::string& staging, const std::string& dir) {
  const std::vector<std::string> fresh = list_files(staging);
  const std::set<std::string> keep(fresh.begin(), fresh.end());
  std::remove((dir + "/summary.json").c_str());  // until the new one is in, DIR claims nothing
  for (const auto& old : read_manifest(dir))
    if (!keep.count(old)) std::remove((dir + "/" + old).c_str());
  auto move = [&](const std::string& name) {
    if (std::rename((staging + "/" + name).c_str(), (dir + "/" + name).c_str()) != 0)
      throw IoError("cannot move '" + name + "' into '" + dir + "': " + std::strerror(errno));
  };
  for (const auto& f : fresh)
    if (f != "summary.json") move(f);
  std::string manifest;
  for (const auto& f : fresh) manifest += f + "\n";
  write_file_atomic(dir + "/" + kManifest, manifest);
  if (keep.count("summary.json")) move("summary.json");
  ::rmdir(staging.c_str());
  return fresh.size();
}

/// The studies of the design, written into `staging`.
int run_into(const Design& design, const RunOptions& options, const std::string& staging);

}  // namespace

int run_design(const Design& design, const RunOptions& options) {
  make_dirs(options.out_dir);
  remove_stale_staging(options.out_dir);
  const std::string staging = options.out_dir + "/" + kStagingPrefix + std::to_string(::getpid());
  if (::mkdir(staging.c_str(), 0755) != 0)
    throw IoError("cannot create '" + staging + "': " + std::strerror(errno));
  try {
    const int code = run_into(design, options, staging);
    const std::size_t n = commit(staging, options.out_dir);
    if (options.log && !options.quiet)
      *options.log << "results: " << options.out_dir << " (" << n << " files, summary.json)\n";
    return code;
  } catch (const IoError&) {
    remove_flat_dir(staging);  // the previous results stay as they were
    throw;
  } catch (const std::invalid_argument&) {
    remove_flat_dir(staging);  // bad input found late: nothing is written (exit 2)
    throw;
  } catch (const std::exception& e) {
    // A computation that failed in a way no study reports by itself: what was written so
    // far goes out with a summary that says so, and the caller reports the reason.
    Json summary = Json::object();
    summary["freeflex_version"] = version();
    summary["design"] = design.source;
    summary["status"] = "failed";
    summary["message"] = std::string(e.what());
    write_file_atomic(staging + "/summary.json", summary.dump());
    commit(staging, options.out_dir);
    throw;
  }
}

namespace {

int run_into(const Design& design, const RunOptions& options, const std::string& staging) {
  RunOutput out(staging, options.quiet ? nullptr : options.log);
  Json summary = Json::object();
  summary["freeflex_version"] = version();
  summary["design"] = design.source;
  summary["title"] = design.title;
  summary["noa"] = design.noa;
  Json studies = Json::object();
  int code = kExitOk;
  bool any = false;
  if (design.free_vibration) {
    run_free_vibration(design, out, studies);
    any = true;
  }
  ManeuverOutcome maneuver;
  if (design.maneuver) {
    maneuver = run_maneuver(design, out, studies, options.quiet);
    code = std::max(code, maneuver.code);
    any = true;
  }
  if (design.simulation && maneuver.code == kExitOk) {
    code = std::max(code, run_simulation(design, out, studies, design.maneuver ? &maneuver : nullptr));
    any = true;
  }
  if (design.controller && maneuver.code == kExitOk) {
    code = std::max(code, run_suppression(design, out, studies, design.maneuver ? &maneuver : nullptr));
    any = true;
  }
  if (!any) out.warn("the design asks for no study; add [free_vibration] or [simulation] (see README, design keys)");
  summary["status"] = code == kExitOk ? "ok" : "failed";
  summary["studies"] = studies;
  Json files = Json::array();
  for (const auto& f : out.files()) files.push_back(f);
  files.push_back("summary.json");
  summary["files"] = files;
  Json warnings = Json::array();
  for (const auto& w : out.warnings()) warnings.push_back(w);
  summary["warnings"] = warnings;
  write_file_atomic(staging + "/summary.json", summary.dump());
  return code;
}

}  // namespace

}  // namespace freeflex
