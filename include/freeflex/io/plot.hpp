#pragma once
// Figures through gnuplot: a script is written beside the data (users can restyle and
// re-run it) and gnuplot renders the PNG to a temporary name that is then renamed.
// gnuplot runs without a shell, under a time limit (PlotOptions); the text a script
// carries (titles, labels) is bounded and stripped of control characters.
#include <array>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "freeflex/enum_names.hpp"

namespace freeflex {

struct PlotSeries {
  std::string data_file;  ///< CSV in the output directory (header line skipped)
  int x_column = 1;       ///< 1-based
  int y_column = 2;       ///< 1-based
  std::string title;
  std::string style = "lines";  ///< gnuplot style: "lines", "points", "linespoints", "lines dt 2" ...
  /// false: the series does not set the y range when another series of its panel does
  /// (a run that stopped out of range, whose last values would flatten the others); it is
  /// drawn clipped at the axes.
  bool sets_range = true;
  /// gnuplot colour ("#rrggbb", see series_color); "": gnuplot's own cycle of 8
  std::string color{};
};

/// Colours told apart in a figure: series_color(i) for i < kSeriesColors are distinct
/// (then they repeat). Give each case of a figure its own index and use it in every panel
/// and figure that shows the case, so that a case keeps its colour.
inline constexpr std::size_t kSeriesColors = 12;
std::string series_color(std::size_t index);

struct PlotPanel {
  std::string title, xlabel, ylabel;
  std::vector<PlotSeries> series;
  bool log_y = false;  ///< logarithmic y axis (points <= 0 are left out by gnuplot)
  /// Horizontal reference lines (e.g. actuator limits), drawn dashed and titled
  /// `hline_title`; with any, the y range is widened to show them with a margin, so
  /// that a command at its limit is not clipped by the axis.
  std::vector<double> hlines{};
  std::string hline_title = "limit";
  /// The x axis ends at the data's first and last x (gnuplot's `autoscale xfix`), not at
  /// the next tic beyond them: a time axis, along which the limit lines then run the whole
  /// width. false for boxes (a histogram's outer bars would be cut in half).
  bool x_to_data = true;
};

/// Panels share their left and right margins (the key's column, as wide as the widest
/// key of the figure), so that their x axes line up; the figure is widened when the keys
/// would leave its plots narrower than about half of it.
struct PlotSpec {
  std::string name;   ///< file stem: NAME.gp and NAME.png
  std::string title;  ///< figure title (above all panels)
  std::vector<PlotPanel> panels;  ///< stacked vertically
  int width_px = 900;  ///< at least: widened for wide keys
  int height_px = 0;  ///< 0: 300 px per panel plus a header
};

/// Bytes of one text (title, label, series title) a figure script carries; longer texts
/// are cut (at a character boundary, ending in "..."). Control characters become blanks
/// and invalid UTF-8 becomes '?': gnuplot's text layout is slow on them (a 41 KB title of
/// tabs took minutes).
inline constexpr std::size_t kMaxFigureTextBytes = 512;

/// The gnuplot found when freeflex was built ("" if none was).
std::string built_in_gnuplot();

/// How figures are rendered.
struct PlotOptions {
  std::string gnuplot = built_in_gnuplot();  ///< path of the program run; "": no PNG is drawn
  double timeout_s = 30.0;                   ///< wall time per figure; then gnuplot's process group is killed
};

/// Throws std::invalid_argument unless timeout_s is in (0, 3600] and gnuplot has no NUL
/// character; the defaults are valid.
void validate(const PlotOptions& options);

struct PlotResult {
  /// drawn; no_gnuplot: none to run; failed: gnuplot could not start or reported an error;
  /// timed_out: stopped at PlotOptions::timeout_s.
  enum class Status { Drawn, NoGnuplot, Failed, TimedOut };
  Status status = Status::Failed;
  std::string message;  ///< why no PNG was drawn ("" when drawn)
  double seconds = 0;   ///< gnuplot's wall time
  bool ok() const { return status == Status::Drawn; }
};

template <>
struct EnumNames<PlotResult::Status> {
  static constexpr const char* what = "plot status";
  static constexpr std::array<std::pair<PlotResult::Status, const char*>, 4> names{
      {{PlotResult::Status::Drawn, "drawn"},
       {PlotResult::Status::NoGnuplot, "no_gnuplot"},
       {PlotResult::Status::Failed, "failed"},
       {PlotResult::Status::TimedOut, "timed_out"}}};
};

/// Writes DIR/NAME.gp and renders DIR/NAME.png with `options.gnuplot`. The data files are
/// left as they are whatever happens; a PNG is either whole or absent. Throws IoError when
/// the script cannot be written.
PlotResult render_plot(const PlotSpec& spec, const std::string& dir, const PlotOptions& options = {});

}  // namespace freeflex
