// Figures through gnuplot: the script beside the data, its text made safe for gnuplot,
// the PNG rendered to a temporary name by gnuplot run under a time limit.
#include "freeflex/io/plot.hpp"

#include <cmath>
#include <algorithm>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

#include "freeflex/io/output.hpp"
#include "io/run_program.hpp"

namespace freeflex {
namespace {

/// Length of the valid UTF-8 sequence starting at s[i], 0 if none starts there.
std::size_t utf8_length(const std::string& s, std::size_t i) {
  const auto c = static_cast<unsigned char>(s[i]);
  std::size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
  if (n == 0 || i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k)
    if ((static_cast<unsigned char>(s[i + k]) & 0xC0) != 0x80) return 0;
  return n;
}

/// `s` as a figure may show it: control characters as blanks, invalid UTF-8 as '?', at
/// most kMaxFigureTextBytes bytes (cut at a character, "..." at the end).
std::string figure_text(const std::string& s) {
  std::string t;
  for (std::size_t i = 0; i < s.size();) {
    const std::size_t n = utf8_length(s, i);
    std::string ch;
    if (n == 0) {
      ch = "?";
      ++i;
    } else {
      const auto c = static_cast<unsigned char>(s[i]);
      ch = (n == 1 && (c < 0x20 || c == 0x7F)) ? std::string(" ") : s.substr(i, n);
      i += n;
    }
    if (t.size() + ch.size() > kMaxFigureTextBytes - 3) {
      t += "...";
      break;
    }
    t += ch;
  }
  return t;
}

/// A gnuplot single-quoted string ('' stands for ').
std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : figure_text(s)) q += (c == '\'') ? std::string("''") : std::string(1, c);
  return q + "'";
}

/// A title as a gnuplot string expression, broken at blanks into lines that fit a figure
/// `width_px` wide (about 8 px a character at Sans 10), at most three ('...' after them).
std::string title_text(const std::string& s, int width_px) {
  const std::string text = figure_text(s);
  const std::size_t width = static_cast<std::size_t>(std::max(40, width_px / 8));
  std::vector<std::string> lines;
  std::size_t at = 0;
  while (at < text.size() && lines.size() < 3) {
    std::size_t end = text.size();
    if (end - at > width) {
      const std::size_t blank = text.rfind(' ', at + width);
      end = blank != std::string::npos && blank > at ? blank : at + width;
      while (end < text.size() && (static_cast<unsigned char>(text[end]) & 0xC0) == 0x80) ++end;  // whole UTF-8 characters
    }
    lines.push_back(text.substr(at, end - at));
    at = end;
    while (at < text.size() && text[at] == ' ') ++at;
  }
  if (at < text.size()) lines.back() += "...";
  std::string expr = quoted(lines.empty() ? std::string() : lines.front());
  for (std::size_t i = 1; i < lines.size(); ++i) expr += ".\"\\n\"." + quoted(lines[i]);
  return expr;
}

std::string seconds_text(double s) {
  std::ostringstream os;
  os << s;
  return os.str();
}

/// Characters (not bytes) of `s` as a figure shows it.
std::size_t shown_length(const std::string& s) {
  std::size_t n = 0;
  for (char c : figure_text(s)) n += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  return n;
}

/// Left margin of every panel, in characters: the y tics ("-0.0005", "1e-12") and label.
constexpr int kLeftMarginChars = 12;
/// About 8 px a character width of the margins at Sans 10, a key's text up to 7 px a
/// character, its sample line and gaps about 80 px.
constexpr double kMarginCharPx = 8.0, kKeyCharPx = 7.0, kKeySamplePx = 80.0;
/// Plots narrower than this (px) widen the figure.
constexpr int kMinPlotWidthPx = 480;

}  // namespace

std::string series_color(std::size_t index) {
  // distinct hues, then darker and greyer ones; no black (the limit lines are black)
  static constexpr std::array<const char*, kSeriesColors> palette{
      "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b",
      "#e377c2", "#17becf", "#7f7f7f", "#bcbd22", "#000080", "#800000"};
  return palette[index % palette.size()];
}

std::string built_in_gnuplot() {
  const std::string g = FREEFLEX_GNUPLOT;
  return g.find("NOTFOUND") == std::string::npos ? g : "";
}

void validate(const PlotOptions& o) {
  if (!(o.timeout_s > 0.0 && o.timeout_s <= 3600.0))
    throw std::invalid_argument("plot options: timeout_s = " + seconds_text(o.timeout_s) + ", expected in (0, 3600]");
  if (o.gnuplot.find('\0') != std::string::npos)
    throw std::invalid_argument("plot options: gnuplot contains a NUL character");
}

PlotResult render_plot(const PlotSpec& spec, const std::string& dir, const PlotOptions& options) {
  validate(options);
  const int panels = static_cast<int>(spec.panels.size());
  const int height = spec.height_px > 0 ? spec.height_px : 60 + 300 * panels;
  // one right margin for all panels: the widest key's text
  std::size_t key_chars = 0;
  for (const auto& p : spec.panels) {
    for (const auto& s : p.series) key_chars = std::max(key_chars, shown_length(s.title));
    if (!p.hlines.empty()) key_chars = std::max(key_chars, shown_length(p.hline_title));
  }
  const int right_margin =
      static_cast<int>(std::ceil((static_cast<double>(key_chars) * kKeyCharPx + kKeySamplePx) / kMarginCharPx));
  const int width = std::max(
      spec.width_px, kMinPlotWidthPx + static_cast<int>((kLeftMarginChars + right_margin) * kMarginCharPx));
  std::ostringstream gp;
  gp << "# freeflex figure '" << spec.name << "': gnuplot " << spec.name << ".gp renders " << spec.name
     << ".png\n"
     << "if (!exists('outfile')) outfile = " << quoted(spec.name + ".png") << "\n"
     << "set terminal pngcairo size " << width << "," << height << " font 'Sans,10'\n"
     << "set output outfile\n"
     << "set datafile separator ','\n"
     << "set grid\nset key outside right top noenhanced\nset termoption noenhanced\n"
     << "set lmargin " << kLeftMarginChars << "\nset rmargin " << right_margin << "\n";
  if (panels > 1)
    gp << "set multiplot layout " << panels << ",1 title " << title_text(spec.title, width) << "\n";
  else
    gp << "set title " << title_text(spec.title, width) << "\n";
  for (const auto& p : spec.panels) {
    if (panels > 1) gp << "set title " << quoted(p.title) << "\n";
    gp << (p.log_y ? "set logscale y\nset format y '%.0e'\n" : "unset logscale y\nset format y '% h'\n");
    gp << "set xlabel " << quoted(p.xlabel) << "\nset ylabel " << quoted(p.ylabel) << "\n";
    gp << (p.x_to_data ? "set autoscale xfix\n" : "set autoscale x\n");
    // Series that set the y range: all, unless some of them do not (then the others).
    std::vector<const PlotSeries*> ranging;
    for (const auto& s : p.series)
      if (s.sets_range) ranging.push_back(&s);
    const bool some_left_out = !ranging.empty() && ranging.size() < p.series.size();
    if (ranging.empty())
      for (const auto& s : p.series) ranging.push_back(&s);
    if (p.log_y && some_left_out) {
      // the positive values of the ranging series, with a factor of 2 as margin
      gp << "set autoscale y\nstats_lo = 1e300\nstats_hi = 0\n";
      for (const PlotSeries* s : ranging)
        gp << "stats " << quoted(s->data_file) << " skip 1 using (column(" << s->y_column << ") > 0 ? column("
           << s->y_column << ") : NaN) nooutput\nstats_lo = (STATS_min < stats_lo) ? STATS_min : stats_lo\n"
              "stats_hi = (STATS_max > stats_hi) ? STATS_max : stats_hi\n";
      gp << "set yrange [stats_lo / 2 : stats_hi * 2]\n";
    } else if (!p.hlines.empty() || some_left_out) {
      // the data's range and the lines', with 10% of the larger span as margin
      if (p.hlines.empty())
        gp << "set autoscale y\nstats_lo = 1e300\nstats_hi = -1e300\n";
      else
        gp << "set autoscale y\nstats_lo = " << std::min(0.0, *std::min_element(p.hlines.begin(), p.hlines.end()))
           << "\nstats_hi = " << std::max(0.0, *std::max_element(p.hlines.begin(), p.hlines.end())) << "\n";
      for (const PlotSeries* s : ranging)
        gp << "stats " << quoted(s->data_file) << " skip 1 using " << s->y_column
           << " nooutput\nstats_lo = (STATS_min < stats_lo) ? STATS_min : stats_lo\n"
              "stats_hi = (STATS_max > stats_hi) ? STATS_max : stats_hi\n";
      gp << "stats_pad = 0.1 * (stats_hi - stats_lo + 1e-12)\nset yrange [stats_lo - stats_pad : stats_hi + stats_pad]\n";
    }
    gp << "plot ";
    for (std::size_t i = 0; i < p.series.size(); ++i) {
      const auto& s = p.series[i];
      gp << (i ? ", \\\n     " : "") << quoted(s.data_file) << " skip 1 using " << s.x_column << ":" << s.y_column
         << " with " << s.style << " lw 2";
      if (!s.color.empty()) gp << " lc rgb " << quoted(s.color);
      gp << " title " << quoted(s.title);
    }
    for (std::size_t i = 0; i < p.hlines.size(); ++i)
      gp << ", \\\n     " << p.hlines[i] << " with lines dt 3 lw 1.5 lc rgb 'black' title "
         << quoted(i == 0 ? p.hline_title : "");
    gp << "\n";
    if (!p.hlines.empty() || some_left_out) gp << "set autoscale y\n";
  }
  if (panels > 1) gp << "unset multiplot\n";
  write_file_atomic(dir + "/" + spec.name + ".gp", gp.str());

  PlotResult r;
  const std::string rerun = "; run 'gnuplot " + spec.name + ".gp' in " + dir;
  if (options.gnuplot.empty()) {
    r.status = PlotResult::Status::NoGnuplot;
    r.message = "no gnuplot (none was found when freeflex was built, or FREEFLEX_GNUPLOT is empty)" + rerun;
    return r;
  }
  const std::string tmp = spec.name + ".png.tmp." + std::to_string(::getpid());
  const std::string tmp_path = dir + "/" + tmp;
  const io_detail::ProgramRun run =
      io_detail::run_program({options.gnuplot, "-e", "outfile='" + tmp + "'", spec.name + ".gp"}, dir, options.timeout_s);
  r.seconds = run.seconds;
  if (!run.ok()) std::remove(tmp_path.c_str());
  using S = io_detail::ProgramRun::Status;
  switch (run.status) {
    case S::NotStarted:
      r.status = PlotResult::Status::Failed;
      r.message = run.error + rerun;
      return r;
    case S::TimedOut:
      r.status = PlotResult::Status::TimedOut;
      r.message = "gnuplot did not finish " + spec.name + ".gp within " + seconds_text(options.timeout_s) +
                  " s and was stopped" + rerun;
      return r;
    case S::Signaled:
      r.status = PlotResult::Status::Failed;
      r.message = "gnuplot was killed by signal " + std::to_string(run.signal) + " on " + spec.name + ".gp" + rerun;
      return r;
    case S::Exited:
      if (run.exit_code != 0) {
        r.status = PlotResult::Status::Failed;
        r.message = "gnuplot failed on " + spec.name + ".gp (exit " + std::to_string(run.exit_code) + "): " + run.output;
        return r;
      }
  }
  if (std::rename(tmp_path.c_str(), (dir + "/" + spec.name + ".png").c_str()) != 0) {
    std::remove(tmp_path.c_str());
    r.status = PlotResult::Status::Failed;
    r.message = "could not rename the rendered " + spec.name + ".png";
    return r;
  }
  r.status = PlotResult::Status::Drawn;
  return r;
}

}  // namespace freeflex
