// Result files: CSV text, the all-or-nothing file writer, figure titles.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

#include "freeflex/io/output.hpp"
#include "freeflex/io/plot.hpp"
#include "support/cli.hpp"
#include "support/files.hpp"

using namespace freeflex;
using Catch::Matchers::Contains;

TEST_CASE("CSV rows use the shortest digits that read back to the same double, and NaN is an empty cell", "[io]") {
  Eigen::MatrixXd data(2, 3);
  data << 0.1, -2.5e-300, std::numeric_limits<double>::quiet_NaN(), 1.0 / 3.0, 0.0, 1e22;
  std::ostringstream os;
  write_csv(os, {"t", "a", "b"}, data);
  CHECK(os.str() == "t,a,b\n0.1,-2.5e-300,\n0.3333333333333333,0,1e+22\n");
  // round trip: every number written reads back to the same double
  std::istringstream in(os.str());
  std::string line, cell;
  std::getline(in, line);  // header
  for (Eigen::Index i = 0; i < data.rows(); ++i) {
    REQUIRE(std::getline(in, line));
    std::istringstream row(line);
    for (Eigen::Index j = 0; j < data.cols(); ++j) {
      std::getline(row, cell, ',');
      if (std::isnan(data(i, j))) CHECK(cell.empty());
      else CHECK(std::stod(cell) == data(i, j));
    }
  }
  CHECK_THROWS_AS(write_csv(os, {"t"}, data), std::invalid_argument);
}

TEST_CASE("a file is replaced whole or not at all", "[io]") {
  const std::string dir = freeflex_test::temp_path("output");  // per process: concurrent test runs do not collide
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/r.csv";
  write_file_atomic(path, "old\n");
  // A writer that fails half way leaves the old file and no temporary behind.
  CHECK_THROWS_AS(write_file_atomic(path,
                                    [](std::ostream& os) {
                                      os << "half";
                                      throw std::runtime_error("computation failed");
                                    }),
                  std::runtime_error);
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  CHECK(ss.str() == "old\n");
  int entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++entries;
  CHECK(entries == 1);
  // A directory that does not exist: IoError naming the path.
  CHECK_THROWS_AS(write_file_atomic(dir + "/missing/r.csv", "x"), IoError);
  std::filesystem::remove_all(dir);
}

TEST_CASE("a long figure title is broken into lines the figure's width holds", "[io]") {
  const std::string dir = freeflex_test::temp_path("plot_title");
  std::filesystem::create_directories(dir);
  PlotSpec spec;
  spec.name = "t";
  spec.width_px = 900;  // about 112 characters a line at Sans 10
  spec.title = "Feedback actuators' commands, open loop and under TV-LQR: Rest-to-rest rotation: vibration-aware "
               "optimum, rigid optimum, TV-LQR, bang-bang";  // 134 characters: cut at both sides before
  spec.panels.push_back({"panel", "t [s]", "y", {}});
  spec.panels.push_back({"other", "t [s]", "y", {}});
  PlotOptions no_gnuplot;
  no_gnuplot.gnuplot = "";
  render_plot(spec, dir, no_gnuplot);
  const std::string gp = freeflex_test::read_text(dir + "/t.gp");
  CHECK_THAT(gp, Contains("title 'Feedback actuators'' commands, open loop and under TV-LQR: Rest-to-rest rotation: "
                          "vibration-aware optimum, rigid'.\"\\n\".'optimum, TV-LQR, bang-bang'"));
  spec.title = std::string(600, 'x');  // no blank to break at: cut at the width, three lines at most
  render_plot(spec, dir, no_gnuplot);
  const std::string cut = freeflex_test::read_text(dir + "/t.gp");
  CHECK_THAT(cut, Contains("'" + std::string(112, 'x') + "'.\"\\n\".'" + std::string(112, 'x') + "'.\"\\n\".'" +
                           std::string(112, 'x') + "...'"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("a series that does not set the y range is left out of it, not of the plot", "[io][figures]") {
  // a run that stopped out of range: its last values flattened the completed runs' curves
  const std::string dir = freeflex_test::temp_path("plot_range");
  std::filesystem::create_directories(dir);
  PlotSpec spec;
  spec.name = "r";
  spec.panels.push_back({"tip", "t [s]", "w [m]", {{"good.csv", 1, 2, "completed", "lines"}}});
  PlotSeries stopped{"stopped.csv", 1, 2, "stopped (stopped at 1 s: out of range)", "lines dt 2"};
  stopped.sets_range = false;
  spec.panels[0].series.push_back(stopped);
  spec.panels.push_back(spec.panels[0]);
  spec.panels[1].log_y = true;
  PlotOptions no_gnuplot;
  no_gnuplot.gnuplot = "";
  render_plot(spec, dir, no_gnuplot);
  const std::string gp = freeflex_test::read_text(dir + "/r.gp");
  CHECK_THAT(gp, Contains("stats 'good.csv' skip 1 using 2 nooutput"));
  CHECK_THAT(gp, Contains("stats 'good.csv' skip 1 using (column(2) > 0 ? column(2) : NaN) nooutput"));
  CHECK(gp.find("stats 'stopped.csv'") == std::string::npos);
  CHECK_THAT(gp, Contains("set yrange [stats_lo - stats_pad : stats_hi + stats_pad]"));
  CHECK_THAT(gp, Contains("'stopped.csv' skip 1 using 1:2 with lines dt 2 lw 2"));
  // every series setting the range (or none): gnuplot's own autoscale, no stats
  spec.panels[0].series[1].sets_range = true;
  spec.panels[1].series[0].sets_range = false;
  render_plot(spec, dir, no_gnuplot);
  CHECK(freeflex_test::read_text(dir + "/r.gp").find("stats ") == std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST_CASE("figures have 12 distinct series colours and panels that share their margins", "[io][figures]") {
  std::set<std::string> colours;
  for (std::size_t i = 0; i < kSeriesColors; ++i) colours.insert(series_color(i));
  CHECK(colours.size() == 12);
  CHECK(kSeriesColors >= 12);
  CHECK(series_color(kSeriesColors) == series_color(0));
  const std::string dir = freeflex_test::temp_path("plot_colours");
  std::filesystem::create_directories(dir);
  PlotSpec spec;
  spec.name = "c";
  spec.panels.push_back({"a", "t [s]", "y", {{"a.csv", 1, 2, "short", "lines", true, series_color(3)}}});
  spec.panels.push_back({"b", "t [s]", "y", {{"b.csv", 1, 2, std::string(100, 'k'), "lines dt 2"}}});
  PlotOptions no_gnuplot;
  no_gnuplot.gnuplot = "";
  render_plot(spec, dir, no_gnuplot);
  const std::string gp = freeflex_test::read_text(dir + "/c.gp");
  CHECK_THAT(gp, Contains("using 1:2 with lines lw 2 lc rgb '" + series_color(3) + "' title 'short'"));
  CHECK_THAT(gp, Contains("using 1:2 with lines dt 2 lw 2 title '"));  // no colour: gnuplot's cycle
  // one left and one right margin for both panels, the right one holding the widest key
  CHECK(gp.find("set lmargin 12\nset rmargin 98\n") < gp.find("set multiplot"));
  CHECK(gp.find("set lmargin", gp.find("set multiplot")) == std::string::npos);
  CHECK_THAT(gp, Contains("set terminal pngcairo size 1360,"));  // widened: the plots keep 480 px
  std::filesystem::remove_all(dir);
}

TEST_CASE("a time axis ends at the data, so that limit lines run its whole width", "[io][figures]") {
  // the axis ran to the next tic beyond the data (2.17 s: to 2.2) and the limits stopped short
  const std::string dir = freeflex_test::temp_path("plot_xfix");
  std::filesystem::create_directories(dir);
  PlotSpec spec;
  spec.name = "x";
  spec.panels.push_back({"commands", "t [s]", "u", {{"u.csv", 1, 2, "u", "lines"}}});
  spec.panels[0].hlines = {-1.0, 1.0};
  spec.panels.push_back({"histogram", "E", "samples", {{"h.csv", 1, 2, "samples", "boxes"}}});
  spec.panels[1].x_to_data = false;
  PlotOptions no_gnuplot;
  no_gnuplot.gnuplot = "";
  render_plot(spec, dir, no_gnuplot);
  const std::string gp = freeflex_test::read_text(dir + "/x.gp");
  const auto second = gp.find("set title 'histogram'");
  REQUIRE(second != std::string::npos);
  CHECK(gp.find("set autoscale xfix\n") < second);
  CHECK(gp.find("set autoscale x\n", second) != std::string::npos);
  CHECK(gp.find("set autoscale xfix\n", second) == std::string::npos);
  std::filesystem::remove_all(dir);
}
