// freeflex command line: `freeflex modes DESIGN`, `freeflex run DESIGN --out DIR`.
// Exit codes: 0 ok, 1 numerical failure, 2 bad input (nothing written), 3 write failure.
#include <cstring>
#include <iomanip>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "freeflex/app/run.hpp"
#include "freeflex/model/basis.hpp"
#include "freeflex/version.hpp"

namespace {

using namespace freeflex;

const char* kUsage =
    "freeflex " FREEFLEX_VERSION " - controller-design workbench for free-free flexible beams\n"
    "\n"
    "usage:\n"
    "  freeflex modes DESIGN [--noa N] [--format table|csv|json]\n"
    "      elastic natural frequencies of the design's beam (ascending)\n"
    "  freeflex run DESIGN --out DIR [--quiet]\n"
    "      does what the design asks; writes results and summary.json into DIR\n"
    "  freeflex --version | --help\n"
    "\n"
    "exit codes: 0 ok, 1 numerical failure, 2 bad input (nothing written), 3 cannot write results\n";

struct UsageError {
  std::string message;
};

struct Args {
  std::string command, design, out, format = "table";
  std::optional<int> noa;
  bool quiet = false;
};

Args parse_args(int argc, char** argv) {
  Args a;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&](const std::string& opt) -> std::string {
      if (i + 1 >= argc) throw UsageError{opt + " needs a value"};
      return argv[++i];
    };
    if (s == "--out") a.out = value(s);
    else if (s == "--format") a.format = value(s);
    else if (s == "--quiet") a.quiet = true;
    else if (s == "--noa") {
      const std::string v = value(s);
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0' || n < 1 || n > kMaxNoa)
        throw UsageError{"--noa " + v + ": must be a whole number in [1, " + std::to_string(kMaxNoa) + "]"};
      a.noa = static_cast<int>(n);
    } else if (s.size() > 1 && s[0] == '-') throw UsageError{"unknown option '" + s + "'"};
    else pos.push_back(s);
  }
  if (pos.empty()) throw UsageError{"a command is required (modes or run)"};
  a.command = pos[0];
  if (a.command != "modes" && a.command != "run") throw UsageError{"unknown command '" + a.command + "'"};
  if (pos.size() != 2) throw UsageError{"'" + a.command + "' takes exactly one DESIGN file"};
  a.design = pos[1];
  if (a.format != "table" && a.format != "csv" && a.format != "json")
    throw UsageError{"--format " + a.format + ": must be table, csv or json"};
  if (a.command == "run" && a.out.empty()) throw UsageError{"run needs --out DIR"};
  if (a.command == "modes" && !a.out.empty()) throw UsageError{"--out belongs to run, not modes"};
  return a;
}

int cmd_modes(const Args& a, const Design& d) {
  const int noa = a.noa.value_or(d.noa);
  const ModeTable t = mode_table(d, noa);
  std::cout << std::setprecision(12);
  if (a.format == "csv") {
    std::cout << "mode,omega_rad_s,freq_hz,lambda\n";
    for (int k = 0; k < t.lambda.size(); ++k)
      std::cout << k + 1 << ',' << t.omega_rad_s(k) << ',' << t.freq_hz(k) << ',' << t.lambda(k) << '\n';
  } else if (a.format == "json") {
    Json j = Json::object();
    j["design"] = d.source;
    j["noa"] = noa;
    j["omega_rad_s"] = Json::from(t.omega_rad_s);
    j["freq_hz"] = Json::from(t.freq_hz);
    j["lambda"] = Json::from(t.lambda);
    std::cout << j.dump();
  } else {
    std::cout << "elastic modes of '" << d.source << "', NOA = " << noa << "\n"
              << std::setw(5) << "mode" << std::setw(18) << "omega [rad/s]" << std::setw(16) << "freq [Hz]"
              << std::setw(14) << "lambda" << '\n';
    for (int k = 0; k < t.lambda.size(); ++k)
      std::cout << std::setw(5) << k + 1 << std::fixed << std::setprecision(6) << std::setw(18) << t.omega_rad_s(k)
                << std::setw(16) << t.freq_hz(k) << std::setw(14) << t.lambda(k) << std::defaultfloat << '\n';
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0)) {
    std::cout << kUsage;
    return 0;
  }
  if (argc >= 2 && std::strcmp(argv[1], "--version") == 0) {
    std::cout << "freeflex " << version() << " (" << dependency_versions() << ")\n";
    return 0;
  }
  Args args;
  try {
    args = parse_args(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "freeflex: " << e.message << "\n\n" << kUsage;
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
    if (args.command == "modes") return cmd_modes(args, design);
    RunOptions opt;
    opt.out_dir = args.out;
    opt.quiet = args.quiet;
    opt.log = &std::cout;
    return run_design(design, opt);
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
