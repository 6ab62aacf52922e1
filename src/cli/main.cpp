// freeflex command line: `freeflex modes DESIGN`, `freeflex run DESIGN --out DIR`, parsed
// by CLI11. Results (the modes table, the closing lines) go to stdout; warnings and
// errors to stderr. Exit codes: 0 ok, 1 numerical failure (its reason on stderr, also
// with --quiet), 2 bad input (nothing written), 3 results could not be written.
#include <CLI/CLI.hpp>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <limits>
#include <iostream>
#include <string>

#include "freeflex/analysis/free_vibration.hpp"
#include "freeflex/app/run.hpp"
#include "freeflex/model/beam.hpp"
#include "freeflex/io/output.hpp"
#include "freeflex/model/basis.hpp"
#include "freeflex/model/modal_integrals.hpp"
#include "freeflex/version.hpp"

namespace {

using namespace freeflex;

/// A command line that names an option or a value freeflex refuses (exit 2).
struct UsageError {
  std::string message;
};

struct Args {
  std::string design, out, format = "table", noa_text;
  int noa = 0;  ///< 0: the design's model.noa
  bool quiet = false;
  std::string spin_text;        ///< --spin: steady spin rate [rad/s], reference frame held
  std::string stiffening = "";  ///< --stiffening on|off (default: the design's model)
  PlotOptions plot;
  int threads = 0;  ///< [sweep] threads, 0: every core
};

/// --noa as a number of admissible functions; throws UsageError.
int parse_noa(const std::string& text) {
  char* end = nullptr;
  const long n = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || n < 1 || n > kMaxNoa)
    throw UsageError{"--noa " + text + ": must be a whole number in [1, " + std::to_string(kMaxNoa) + "]"};
  return static_cast<int>(n);
}

/// `freeflex modes --spin W`: frequencies with the reference frame held spinning at W
/// (docs/theory.md eq. 14.12); NaN for a mode the spin has buckled (ω² < 0).
int cmd_spinning_modes(const Args& a, const Design& d, int noa) {
  char* end = nullptr;
  const double spin = a.spin_text.empty() ? 0.0 : std::strtod(a.spin_text.c_str(), &end);
  if (!a.spin_text.empty() && (*end != '\0' || !std::isfinite(spin) || std::abs(spin) > 1e6))
    throw UsageError{"--spin " + a.spin_text + ": must be a number of rad/s in [-1e6, 1e6]"};
  const bool stiff = a.stiffening.empty() ? d.geometric_stiffening : a.stiffening == "on";
  const Beam beam(d.beam);
  const Eigen::VectorXd w2 = spinning_frequencies_squared(stiffened_modal_integrals(beam, *make_basis(beam, noa, d.basis)), spin, stiff);
  auto omega = [](double x) { return x >= 0.0 ? std::sqrt(x) : std::numeric_limits<double>::quiet_NaN(); };
  std::cout << std::setprecision(12);
  if (a.format == "csv") {
    std::cout << "mode,omega_rad_s,omega2\n";
    for (int k = 0; k < w2.size(); ++k) std::cout << k + 1 << ',' << omega(w2(k)) << ',' << w2(k) << '\n';
  } else if (a.format == "json") {
    nlohmann::ordered_json j;
    j["design"] = d.source;
    j["noa"] = noa;
    j["spin_rad_s"] = spin;
    j["geometric_stiffening"] = stiff;
    j["omega2"] = std::vector<double>(w2.data(), w2.data() + w2.size());
    std::cout << j.dump(2) << '\n';
  } else {
    std::cout << "elastic modes of '" << d.source << "', NOA = " << noa << ", spinning at " << spin
              << " rad/s with the reference frame held, geometric stiffening " << (stiff ? "on" : "off") << "\n"
              << std::setw(5) << "mode" << std::setw(18) << "omega [rad/s]" << std::setw(20) << "omega^2" << '\n';
    for (int k = 0; k < w2.size(); ++k)
      std::cout << std::setw(5) << k + 1 << std::fixed << std::setprecision(6) << std::setw(18) << omega(w2(k))
                << std::setw(20) << w2(k) << std::defaultfloat << (w2(k) < 0.0 ? "  (buckled)" : "") << '\n';
  }
  return kExitOk;
}

int cmd_modes(const Args& a, const Design& d) {
  const int noa = a.noa > 0 ? a.noa : d.noa;
  if (!a.spin_text.empty() || !a.stiffening.empty()) return cmd_spinning_modes(a, d, noa);
  // an error estimate where no closed form gives the exact frequencies (docs/theory.md 4b)
  const bool estimate = !has_exact_modes(d);
  const ModeTable t = mode_table(d, noa, estimate);
  const bool fe = d.basis.kind == BasisOptions::Kind::FiniteElement;
  std::cout << std::setprecision(12);
  if (a.format == "csv") {
    std::cout << "mode,omega_rad_s,freq_hz,lambda" << (estimate ? ",error_estimate" : "") << '\n';
    for (int k = 0; k < t.lambda.size(); ++k) {
      std::cout << k + 1 << ',' << t.omega_rad_s(k) << ',' << t.freq_hz(k) << ',' << t.lambda(k);
      if (estimate) {
        std::cout << ',';
        // empty cell where there is no estimate
        if (std::isfinite(t.error_estimate(k))) std::cout << std::setprecision(3) << t.error_estimate(k);
        std::cout << std::setprecision(12);
      }
      std::cout << '\n';
    }
  } else if (a.format == "json") {
    auto array = [](const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
    nlohmann::ordered_json j;
    j["design"] = d.source;
    j["noa"] = noa;
    if (fe) {
      j["basis"] = to_string(d.basis.kind);
      j["elements"] = d.basis.finite_element.elements;
      j["element_order"] = d.basis.finite_element.order;
      if (d.basis.finite_element.modes != FiniteElementOptions::Modes::FreeFree)  // the default: as before
        j["fe_modes"] = to_string(d.basis.finite_element.modes);
    }
    j["omega_rad_s"] = array(t.omega_rad_s);
    j["freq_hz"] = array(t.freq_hz);
    j["lambda"] = array(t.lambda);
    if (estimate) {
      // NaN (no estimate) is not JSON: null
      nlohmann::ordered_json err = nlohmann::ordered_json::array();
      for (int k = 0; k < t.error_estimate.size(); ++k)
        err.push_back(std::isfinite(t.error_estimate(k)) ? nlohmann::ordered_json(t.error_estimate(k)) : nullptr);
      j["error_estimate"] = err;
      j["error_method"] = t.error_method;
    }
    std::cout << j.dump(2) << '\n';
  } else {
    std::cout << "elastic modes of '" << d.source << "', ";
    if (fe)
      std::cout << noa << " modes of " << d.basis.finite_element.elements
                << (d.basis.finite_element.order == 5 ? " quintic" : " cubic") << " elements"
                << (d.basis.finite_element.modes == FiniteElementOptions::Modes::ClampedAtReference ? ", clamped at o"
                                                                                                     : "")
                << "\n";
    else
      std::cout << "NOA = " << noa << "\n";
    std::cout << std::setw(5) << "mode" << std::setw(18) << "omega [rad/s]" << std::setw(16) << "freq [Hz]"
              << std::setw(14) << "lambda" << (estimate ? "   error est." : "") << '\n';
    for (int k = 0; k < t.lambda.size(); ++k) {
      std::cout << std::setw(5) << k + 1 << std::fixed << std::setprecision(6) << std::setw(18) << t.omega_rad_s(k)
                << std::setw(16) << t.freq_hz(k) << std::setw(14) << t.lambda(k);
      if (estimate) std::cout << std::scientific << std::setprecision(1) << std::setw(13) << t.error_estimate(k);
      std::cout << std::defaultfloat << '\n';
    }
    if (estimate)
      std::cout << "error est.: relative (omega - exact) / omega, " << t.error_method
                << (fe ? "" : " (a Ritz estimate's error is at least this)") << '\n';
  }
  return kExitOk;
}

/// The figures' gnuplot and its time limit: FREEFLEX_GNUPLOT (a path; empty: no figures
/// drawn) and FREEFLEX_GNUPLOT_TIMEOUT_S override the defaults. Throws UsageError.
PlotOptions plot_options_from_environment() {
  PlotOptions o;
  if (const char* g = std::getenv("FREEFLEX_GNUPLOT")) o.gnuplot = g;
  if (const char* t = std::getenv("FREEFLEX_GNUPLOT_TIMEOUT_S")) {
    char* end = nullptr;
    const double v = std::strtod(t, &end);
    if (*t == '\0' || *end != '\0' || !(v > 0.0 && v <= 3600.0))
      throw UsageError{"FREEFLEX_GNUPLOT_TIMEOUT_S = '" + std::string(t) + "': must be a number of seconds in (0, 3600]"};
    o.timeout_s = v;
  }
  return o;
}

int cmd_run(const Args& a, const Design& d) {
  RunOptions opt;
  opt.out_dir = a.out;
  opt.plot = a.plot;
  opt.quiet = a.quiet;
  opt.log = &std::cout;
  opt.errors = &std::cerr;
  opt.sweep.threads = a.threads;
  const RunResult r = run_design(d, opt);
  if (!r.ok()) std::cerr << "freeflex: failed: " << r.message << '\n';
  return r.exit_code();
}

}  // namespace

int main(int argc, char** argv) {
#ifdef __GLIBC__
  // Most runs are short and their heaps small (2.5 MB for the slew of docs/benchmarks.md):
  // keep what a run frees instead of returning it to the kernel and faulting it in again
  // (glibc starts by trimming the heap's top past 128 kB and mapping blocks of 128 kB or
  // more on their own). The slew's run: 1 138 page faults → 875, 6% less CPU time with
  // the optimizer's two changes of the same day. A long run (a [sweep]'s threads) then
  // keeps each heap at its peak instead of shrinking it; it does not grow beyond it.
  // 32 MiB is the largest mmap threshold every glibc accepts on 64-bit; if one is refused,
  // none is set (the trim and pad settings alone would freeze the adaptive threshold).
  if (mallopt(M_MMAP_THRESHOLD, 32 << 20) == 1) {
    mallopt(M_TRIM_THRESHOLD, 128 << 20);
    mallopt(M_TOP_PAD, 16 << 20);
  }
#endif
  CLI::App app{"freeflex " FREEFLEX_VERSION " - controller-design workbench for free-free flexible beams", "freeflex"};
  app.footer("exit codes: 0 ok, 1 numerical failure, 2 bad input (nothing written), 3 cannot write results");
  app.set_version_flag("--version", "freeflex " + version() + " (" + dependency_versions() + ")");
  app.require_subcommand(1);
  Args args;
  CLI::App* modes = app.add_subcommand("modes", "elastic natural frequencies of the design's beam (ascending)");
  modes->add_option("DESIGN", args.design, "design file (TOML)")->required();
  modes->add_option("--noa", args.noa_text, "number of shape functions (admissible functions, or finite-element modes kept), 1..100 (default: the design's model.noa)");
  modes->add_option("--format", args.format, "table, csv or json")->check(CLI::IsMember({"table", "csv", "json"}));
  modes->add_option("--spin", args.spin_text,
                    "steady spin rate [rad/s]: frequencies with the reference frame held spinning (default 0 with --stiffening)");
  modes->add_option("--stiffening", args.stiffening, "on or off: geometric stiffening under --spin (default: the design's model)")
      ->check(CLI::IsMember({"on", "off"}));
  CLI::App* run = app.add_subcommand("run", "does what the design asks; writes results and summary.json into DIR");
  run->add_option("DESIGN", args.design, "design file (TOML)")->required();
  run->add_option("--out", args.out, "output directory (created if needed)")->required();
  run->add_flag("--quiet", args.quiet, "no progress or warnings; a failure's reason is still printed");
  run->add_option("--threads", args.threads, "threads of a [sweep] (default 0: every core); results do not depend on it")
      ->check(CLI::Range(0, 4096));
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::cout << app.help();
    return kExitOk;
  } catch (const CLI::CallForVersion& e) {
    std::cout << e.what() << '\n';
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // help of a subcommand
    std::cerr << "freeflex: " << e.what() << "\n(run 'freeflex --help' or 'freeflex COMMAND --help')\n";
    return kExitBadInput;
  }
  try {
    if (!args.noa_text.empty()) args.noa = parse_noa(args.noa_text);
    args.plot = plot_options_from_environment();
  } catch (const UsageError& e) {
    std::cerr << "freeflex: " << e.message << '\n';
    return kExitBadInput;
  }
  Design design;
  try {
    design = load_design(args.design);
  } catch (const DesignError& e) {
    std::cerr << e.what() << '\n';
    const auto n = e.problems().size();
    std::cerr << "freeflex: " << n << (n == 1 ? " problem" : " problems") << " in the design; nothing was run\n";
    return kExitBadInput;
  }
  try {
    return modes->parsed() ? cmd_modes(args, design) : cmd_run(args, design);
  } catch (const UsageError& e) {
    std::cerr << "freeflex: " << e.message << '\n';
    return kExitBadInput;
  } catch (const std::invalid_argument& e) {
    std::cerr << "freeflex: " << e.what() << '\n';
    return kExitBadInput;
  } catch (const IoError& e) {
    std::cerr << "freeflex: " << e.what() << '\n';
    return kExitIoFailure;
  } catch (const std::exception& e) {  // a computation failed without a study reporting it
    std::cerr << "freeflex: failed: " << e.what() << '\n';
    return kExitNumericalFailure;
  }
}
