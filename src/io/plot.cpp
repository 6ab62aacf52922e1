// Figures through gnuplot: the script beside the data, the PNG rendered to a temporary name.
#include "freeflex/io/plot.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

#include "freeflex/io/output.hpp"

namespace freeflex {
namespace {

std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("''") : std::string(1, c);
  return q + "'";
}

std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

std::string render_plot(const PlotSpec& spec, const std::string& dir) {
  const int panels = static_cast<int>(spec.panels.size());
  const int height = spec.height_px > 0 ? spec.height_px : 60 + 300 * panels;
  std::ostringstream gp;
  gp << "# freeflex figure '" << spec.name << "': gnuplot " << spec.name << ".gp renders " << spec.name
     << ".png\n"
     << "if (!exists('outfile')) outfile = " << quoted(spec.name + ".png") << "\n"
     << "set terminal pngcairo size " << spec.width_px << "," << height << " font 'Sans,10'\n"
     << "set output outfile\n"
     << "set datafile separator ','\n"
     << "set grid\nset key outside right top noenhanced\nset termoption noenhanced\n";
  if (panels > 1)
    gp << "set multiplot layout " << panels << ",1 title " << quoted(spec.title) << "\n";
  else
    gp << "set title " << quoted(spec.title) << "\n";
  for (const auto& p : spec.panels) {
    if (panels > 1) gp << "set title " << quoted(p.title) << "\n";
    gp << (p.log_y ? "set logscale y\nset format y '%.0e'\n" : "unset logscale y\nset format y '% h'\n");
    gp << "set xlabel " << quoted(p.xlabel) << "\nset ylabel " << quoted(p.ylabel) << "\n";
    if (!p.hlines.empty()) {
      // the data's range and the lines', with 10% of the larger span as margin
      gp << "set autoscale y\nstats_lo = " << std::min(0.0, *std::min_element(p.hlines.begin(), p.hlines.end()))
         << "\nstats_hi = " << std::max(0.0, *std::max_element(p.hlines.begin(), p.hlines.end())) << "\n";
      for (const auto& s : p.series)
        gp << "stats " << quoted(s.data_file) << " skip 1 using " << s.y_column
           << " nooutput\nstats_lo = (STATS_min < stats_lo) ? STATS_min : stats_lo\n"
              "stats_hi = (STATS_max > stats_hi) ? STATS_max : stats_hi\n";
      gp << "stats_pad = 0.1 * (stats_hi - stats_lo + 1e-12)\nset yrange [stats_lo - stats_pad : stats_hi + stats_pad]\n";
    }
    gp << "plot ";
    for (std::size_t i = 0; i < p.series.size(); ++i) {
      const auto& s = p.series[i];
      gp << (i ? ", \\\n     " : "") << quoted(s.data_file) << " skip 1 using " << s.x_column << ":" << s.y_column
         << " with " << s.style << " lw 2 title " << quoted(s.title);
    }
    for (std::size_t i = 0; i < p.hlines.size(); ++i)
      gp << ", \\\n     " << p.hlines[i] << " with lines dt 3 lw 1.5 lc rgb 'black' title "
         << quoted(i == 0 ? p.hline_title : "");
    gp << "\n";
    if (!p.hlines.empty()) gp << "set autoscale y\n";
  }
  if (panels > 1) gp << "unset multiplot\n";
  write_file_atomic(dir + "/" + spec.name + ".gp", gp.str());

  const std::string gnuplot = FREEFLEX_GNUPLOT;
  if (gnuplot.empty() || gnuplot.find("NOTFOUND") != std::string::npos)
    return "gnuplot was not found when freeflex was built; run 'gnuplot " + spec.name + ".gp' in " + dir;
  const std::string tmp = spec.name + ".png.tmp." + std::to_string(::getpid());
  const std::string cmd = "cd " + shell_quoted(dir) + " && " + shell_quoted(gnuplot) + " -e " +
                          shell_quoted("outfile='" + tmp + "'") + " " + shell_quoted(spec.name + ".gp") +
                          " 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) return "could not start gnuplot";
  std::string output;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) output += buf;
  const int status = ::pclose(pipe);
  const std::string tmp_path = dir + "/" + tmp;
  if (status != 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::remove(tmp_path.c_str());
    return "gnuplot failed on " + spec.name + ".gp: " + output;
  }
  if (std::rename(tmp_path.c_str(), (dir + "/" + spec.name + ".png").c_str()) != 0)
    return "could not rename the rendered " + spec.name + ".png";
  return "";
}

}  // namespace freeflex
