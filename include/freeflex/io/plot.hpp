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
