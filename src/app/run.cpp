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
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include "freeflex/io/plot.hpp"
#include "freeflex/version.hpp"
#include "util/format.hpp"

namespace freeflex {

/// `text` with the (staging) directory replaced by the one the files end up in.
std::string RunOutput::shown(std::string text) const {
  if (shown_dir_ == dir_) return text;
  for (std::size_t at = text.find(dir_); at != std::string::npos; at = text.find(dir_, at + shown_dir_.size()))
    text.replace(at, dir_.size(), shown_dir_);
  return text;
}

void RunOutput::stream(const std::string& name, const std::function<void(std::ostream&)>& writer) {
  try {
    write_file_atomic(dir_ + "/" + name, writer);
  } catch (const IoError& e) {
    throw IoError(shown(e.what()));  // the staging directory is gone once the run ends
  }
  files_.push_back(name);
}

void RunOutput::write(const std::string& name, const std::string& content) {
  stream(name, [&content](std::ostream& os) { os << content; });
}

void RunOutput::csv(const std::string& name, const std::vector<std::string>& header, const Eigen::MatrixXd& data) {
  stream(name, [&](std::ostream& os) { write_csv(os, header, data); });
}

void RunOutput::plot(const PlotSpec& spec, bool enabled) {
  if (!enabled) return;
  const std::string why = shown(render_plot(spec, dir_));
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
  schedule(now);
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
  schedule(now);
  *log_ << (printed_ ? "" : "\n") << "  " << what << " after " << static_cast<int>(now - start_) << " s\n"
        << std::flush;
  printed_ = true;
}

void ProgressReport::schedule(double now) {
  // sparser as the phase goes on; every_s = 0 prints every call
  next_ = every_s_ > 0.0 ? now + std::max(every_s_, 0.25 * (now - start_)) : now;
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

/// Names of the regular files in `dir` (not recursive, symbolic links not followed);
/// empty if it cannot be read.
std::vector<std::string> list_files(const std::string& dir) {
  std::vector<std::string> names;
  DIR* d = ::opendir(dir.c_str());
  if (!d) return names;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name == "." || name == "..") continue;
    struct stat st {};
    if (::lstat((dir + "/" + name).c_str(), &st) == 0 && S_ISREG(st.st_mode)) names.push_back(name);
  }
  ::closedir(d);
  std::sort(names.begin(), names.end());
  return names;
}

/// Removes a staging directory (a flat directory of files); best effort. Anything else by
/// that name is unlinked: a link goes, never what it points to.
void remove_flat_dir(const std::string& dir) {
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) return;
  if (!S_ISDIR(st.st_mode)) {
    ::unlink(dir.c_str());
    return;
  }
  for (const auto& f : list_files(dir)) std::remove((dir + "/" + f).c_str());
  ::rmdir(dir.c_str());
}

// A run writes into DIR/.freeflex-staging-<pid> and moves its files into DIR only when it
// has finished (successfully or with a reported failure), so DIR never holds a mixture of
// two runs: an interrupted run leaves the previous results as they were. The manifest
// lists the files a run may have left in DIR; the next one removes them first, so no stale
// result outlives the run that replaced it. summary.json goes last. One run at a time
// writes into DIR: it holds a lock on DIR/.freeflex-lock from start to end.
const char* const kManifest = ".freeflex-files";
const char* const kStagingPrefix = ".freeflex-staging-";
const char* const kLock = ".freeflex-lock";

std::vector<std::string> read_manifest(const std::string& dir) {
  std::vector<std::string> names;
  std::ifstream in(dir + "/" + kManifest);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty() && line.find('/') == std::string::npos && line != "." && line != "..") names.push_back(line);
  return names;
}

/// Replaces DIR's manifest, going through a file in `staging` so that a run killed while
/// writing leaves nothing in DIR that no later run would remove.
void write_manifest(const std::string& staging, const std::string& dir, const std::set<std::string>& names) {
  std::string text;
  for (const auto& f : names) text += f + "\n";
  const std::string next = staging + "/" + kManifest;
  write_file_atomic(next, text);
  if (std::rename(next.c_str(), (dir + "/" + kManifest).c_str()) != 0)
    throw IoError("cannot write '" + dir + "/" + kManifest + "': " + std::strerror(errno));
}

/// An exclusive lock on DIR for the life of one run; a second run into DIR fails at once.
class DirLock {
 public:
  explicit DirLock(const std::string& dir) {
    const std::string path = dir + "/" + kLock;
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (fd_ < 0) throw IoError("cannot open '" + path + "': " + std::strerror(errno));
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      ::close(fd_);
      if (err == EWOULDBLOCK)
        throw IoError("another freeflex run is writing into '" + dir +
                      "'; wait for it to finish or give this run another --out");
      throw IoError("cannot lock '" + path + "': " + std::strerror(err));
    }
  }
  DirLock(const DirLock&) = delete;
  DirLock& operator=(const DirLock&) = delete;
  ~DirLock() { ::close(fd_); }  // releases the lock

 private:
  int fd_ = -1;
};

/// Staging directories left by runs that were killed. Only called with DIR locked, so no
/// other run is using one.
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
/// how many it moved. Whenever it stops (killed, or a move fails), the manifest lists every
/// file of either run that DIR may hold, so that the next run clears them all.
std::size_t commit(const std::string& staging, const std::string& dir) {
  const std::vector<std::string> fresh = list_files(staging);
  const std::set<std::string> keep(fresh.begin(), fresh.end());
  const std::vector<std::string> old = read_manifest(dir);
  std::set<std::string> either(keep);
  either.insert(old.begin(), old.end());
  either.insert("summary.json");
  write_manifest(staging, dir, either);
  std::remove((dir + "/summary.json").c_str());  // until the new one is in, DIR claims nothing
  for (const auto& f : old)
    if (!keep.count(f)) std::remove((dir + "/" + f).c_str());
  auto move = [&](const std::string& name) {
    if (std::rename((staging + "/" + name).c_str(), (dir + "/" + name).c_str()) != 0)
      throw IoError("cannot move '" + name + "' into '" + dir + "': " + std::strerror(errno) +
                    " (DIR now holds part of this run's files and no summary.json)");
  };
  for (const auto& f : fresh)
    if (f != "summary.json") move(f);
  write_manifest(staging, dir, keep);
  if (keep.count("summary.json")) move("summary.json");
  ::rmdir(staging.c_str());
  return fresh.size();
}

/// The studies of the design, written through `out`; fills `summary` (all but the
/// files and warnings) and returns the exit code.
int run_into(const Design& design, const RunOptions& options, RunOutput& out, Json& summary);

/// Completes `summary` with the run's files and warnings and writes it as the last file.
void write_summary(RunOutput& out, Json& summary) {
  Json files = Json::array();
  for (const auto& f : out.files()) files.push_back(f);
  files.push_back("summary.json");
  summary["files"] = files;
  Json warnings = Json::array();
  for (const auto& w : out.warnings()) warnings.push_back(w);
  summary["warnings"] = warnings;
  write_file_atomic(out.dir() + "/summary.json", summary.dump());
}

}  // namespace

int run_design(const Design& design, const RunOptions& options) {
  make_dirs(options.out_dir);
  const DirLock lock(options.out_dir);
  remove_stale_staging(options.out_dir);
  const std::string staging = options.out_dir + "/" + kStagingPrefix + std::to_string(::getpid());
  if (::mkdir(staging.c_str(), 0755) != 0)
    throw IoError("cannot create '" + staging + "': " + std::strerror(errno));
  RunOutput out(staging, options.quiet ? nullptr : options.log, options.out_dir);
  Json summary = Json::object();
  summary["freeflex_version"] = version();
  summary["design"] = design.source;
  summary["title"] = design.title;
  summary["noa"] = design.noa;
  try {
    const int code = run_into(design, options, out, summary);
    write_summary(out, summary);
    const std::size_t n = commit(staging, options.out_dir);
    if (options.log && !options.quiet)
      *options.log << "results: " << options.out_dir << " (" << n << " files, summary.json)\n";
    return code;
  } catch (const IoError&) {
    // Before the commit the previous results stay as they were; during it, the manifest
    // lists the files of both runs, and the next run clears them.
    remove_flat_dir(staging);
    throw;
  } catch (const std::invalid_argument&) {
    remove_flat_dir(staging);  // bad input found late: nothing is written (exit 2)
    throw;
  } catch (const std::exception& e) {
    // A computation that failed in a way no study reports by itself: what was written so
    // far goes out with a summary that says so, and the caller reports the reason.
    try {
      summary["status"] = "failed";
      summary["message"] = std::string(e.what());
      write_summary(out, summary);
      commit(staging, options.out_dir);
    } catch (const std::exception& again) {
      remove_flat_dir(staging);
      throw IoError(std::string(again.what()) + "; the run had failed before: " + e.what());
    }
    throw;
  }
}

namespace {

int run_into(const Design& design, const RunOptions& options, RunOutput& out, Json& summary) {
  // The studies fill summary.studies as they go, so that a run that throws half way still
  // reports what it finished. No member is added to `summary` while `studies` refers to it.
  summary["status"] = "failed";
  summary["studies"] = Json::object();
  Json& studies = summary["studies"];
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
  return code;
}

}  // namespace

}  // namespace freeflex
