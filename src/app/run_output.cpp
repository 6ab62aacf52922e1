// A run's files: whole-file writes into the staging directory, figures, warnings
// (app/run_output.hpp).
#include "app/run_output.hpp"

#include <cstdio>

#include "freeflex/io/output.hpp"

namespace freeflex::detail {

/// `text` with the (staging) directory replaced by the one the files end up in.
std::string RunOutput::shown(std::string text) const {
  if (shown_dir_ == dir_) return text;
  for (std::size_t at = text.find(dir_); at != std::string::npos; at = text.find(dir_, at + shown_dir_.size()))
    text.replace(at, dir_.size(), shown_dir_);
  return text;
}

void RunOutput::stream(const std::string& name, const std::function<void(std::ostream&)>& writer) {
  if (dir_.empty()) return;  // a run without an output directory writes nothing
  try {
    write_file_atomic(dir_ + "/" + name, writer);
  } catch (const IoError& e) {
    throw IoError(shown(e.what()));  // the staging directory is gone once the run ends
  }
  files_.push_back(name);
}

void RunOutput::file(const std::string& name, const std::function<void(const std::string& path)>& writer) {
  if (dir_.empty()) return;
  const std::string path = dir_ + "/" + name, tmp = dir_ + "/." + name + ".partial";
  try {
    writer(tmp);
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
      std::remove(tmp.c_str());
      throw IoError("cannot rename '" + tmp + "' to '" + path + "'");
    }
  } catch (const IoError& e) {
    std::remove(tmp.c_str());
    throw IoError(shown(e.what()));
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
  if (!enabled || dir_.empty()) return;
  PlotOptions options = plot_;
  if (gnuplot_stalled_) options.gnuplot.clear();  // the script only: a stalled gnuplot would stall again
  PlotResult r;
  try {
    r = render_plot(spec, dir_, options);
  } catch (const IoError& e) {
    throw IoError(shown(e.what()));
  }
  files_.push_back(spec.name + ".gp");
  if (r.ok()) {
    files_.push_back(spec.name + ".png");
    return;
  }
  if (r.status == PlotResult::Status::TimedOut) gnuplot_stalled_ = true;
  const std::string why = gnuplot_stalled_ && r.status == PlotResult::Status::NoGnuplot
                              ? "gnuplot timed out on an earlier figure, so it was not run again; run 'gnuplot " +
                                    spec.name + ".gp' in " + dir_
                              : r.message;
  warn("figure " + spec.name + ".png not drawn: " + shown(why));
}

void RunOutput::warn(const std::string& message) {
  warnings_.push_back(message);
  if (log_) *log_ << "warning: " << message << '\n';
}

}  // namespace freeflex::detail
