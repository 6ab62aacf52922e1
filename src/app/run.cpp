#include "freeflex/app/run.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <sys/stat.h>

#include "freeflex/io/plot.hpp"
#include "freeflex/version.hpp"

namespace freeflex {

void RunOutput::write(const std::string& name, const std::string& content) {
  write_file_atomic(dir_ + "/" + name, content);
  files_.push_back(name);
}

void RunOutput::csv(const std::string& name, const std::vector<std::string>& header, const Eigen::MatrixXd& data) {
  write(name, csv_text(header, data));
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

/// Creates DIR (and missing parents). Throws std::runtime_error with the reason.
void make_dirs(const std::string& dir) {
  std::string partial;
  std::size_t pos = 0;
  while (pos != std::string::npos) {
    pos = dir.find('/', pos + 1);
    partial = dir.substr(0, pos);
    if (partial.empty()) continue;
    if (::mkdir(partial.c_str(), 0755) != 0 && errno != EEXIST)
      throw std::runtime_error("cannot create output directory '" + partial + "': " + std::strerror(errno));
  }
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw std::runtime_error("output path '" + dir + "' exists and is not a directory");
}

}  // namespace

int run_design(const Design& design, const RunOptions& options) {
  make_dirs(options.out_dir);
  RunOutput out(options.out_dir, options.quiet ? nullptr : options.log);
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
  write_file_atomic(options.out_dir + "/summary.json", summary.dump());
  if (options.log && !options.quiet)
    *options.log << "results: " << options.out_dir << " (" << out.files().size() + 1 << " files, summary.json)\n";
  return code;
}

}  // namespace freeflex
