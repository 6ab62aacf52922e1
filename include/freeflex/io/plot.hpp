#pragma once
// Figures through gnuplot: a script is written beside the data (users can restyle and
// re-run it) and gnuplot renders the PNG to a temporary name that is then renamed.
#include <string>
#include <vector>

namespace freeflex {

struct PlotSeries {
  std::string data_file;  ///< CSV in the output directory (header line skipped)
  int x_column = 1;       ///< 1-based
  int y_column = 2;       ///< 1-based
  std::string title;
  std::string style = "lines";  ///< gnuplot style: "lines", "points", "linespoints", "lines dt 2" ...
};

struct PlotPanel {
  std::string title, xlabel, ylabel;
  std::vector<PlotSeries> series;
  bool log_y = false;  ///< logarithmic y axis (points <= 0 are left out by gnuplot)
  /// Horizontal reference lines (e.g. actuator limits), drawn dashed and titled
  /// `hline_title`; with any, the y range is widened to show them with a margin, so
  /// that a command at its limit is not clipped by the axis.
  std::vector<double> hlines{};
  std::string hline_title = "limit";
};

struct PlotSpec {
  std::string name;   ///< file stem: NAME.gp and NAME.png
  std::string title;  ///< figure title (above all panels)
  std::vector<PlotPanel> panels;  ///< stacked vertically
  int width_px = 900;
  int height_px = 0;  ///< 0: 300 px per panel plus a header
};

/// Writes DIR/NAME.gp and renders DIR/NAME.png. Returns "" on success, otherwise the
/// reason (gnuplot missing or failed); the data files are left as they are.
std::string render_plot(const PlotSpec& spec, const std::string& dir);

}  // namespace freeflex
