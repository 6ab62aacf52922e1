#pragma once
// Where a run's files go: every file written whole into the staging directory, counted
// among the run's files; figures whose rendering fails become warnings (after gnuplot
// has timed out once, the later figures get their scripts only). Without a directory
// nothing is written (a run for its results only). Private to src/.
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/io/plot.hpp"

namespace freeflex::detail {

class RunOutput {
 public:
  /// Files go into `dir`; messages name `shown_dir` (where they end up) if it is given.
  /// Warnings are printed on `warnings_log` (may be null) as they happen.
  RunOutput(std::string dir, std::ostream* warnings_log, std::string shown_dir = {}, PlotOptions plot = {})
      : dir_(std::move(dir)),
        shown_dir_(shown_dir.empty() ? dir_ : std::move(shown_dir)),
        log_(warnings_log),
        plot_(std::move(plot)) {}
  void write(const std::string& name, const std::string& content);
  void csv(const std::string& name, const std::vector<std::string>& header, const Eigen::MatrixXd& data);
  /// A file a library writes by path (a .mat file): `writer` writes a temporary path in
  /// dir(), which is then renamed to `name` and counted among the run's files.
  void file(const std::string& name, const std::function<void(const std::string& path)>& writer);
  /// Renders a plot (unless plots are off); a failure becomes a warning, not an error.
  void plot(const PlotSpec& spec, bool enabled);
  void warn(const std::string& message);
  const std::string& dir() const { return dir_; }
  const std::vector<std::string>& files() const { return files_; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// `text` (a message) with the staging directory replaced by the one the files end up
  /// in: the staging directory is gone once the run ends.
  std::string shown(std::string text) const;

 private:
  /// Writes `name` in dir() through `writer` and counts it among the run's files.
  void stream(const std::string& name, const std::function<void(std::ostream&)>& writer);

  std::string dir_, shown_dir_;
  std::ostream* log_;
  PlotOptions plot_;
  bool gnuplot_stalled_ = false;  // gnuplot timed out on an earlier figure
  std::vector<std::string> files_, warnings_;
};

}  // namespace freeflex::detail
