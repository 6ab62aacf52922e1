// Design files: reading and validating a whole file (the section readers are in
// io/design_*.cpp), and what a design derives (force elements, excitation).
#include "freeflex/io/design.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "freeflex/model/basis.hpp"
#include "io/design_sections.hpp"

namespace freeflex {
namespace {

using io_detail::Outputs;
using io_detail::Problems;
using io_detail::Section;
namespace lim = design_limits;

std::string join_lines(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& line : v) s += (s.empty() ? "" : "\n") + line;
  return s;
}

}  // namespace

std::vector<ForceElement> Design::force_elements() const {
  std::vector<ForceElement> e;
  for (const auto& l : loads) e.push_back(l.element);
  for (const auto& a : actuators) e.push_back(a.element);
  return e;
}

FlexibleBody Design::body() const {
  return FlexibleBody(Beam(beam), noa, basis, force_elements(), damping_ratios, geometric_stiffening);
}

Excitation Design::excitation() const {
  Excitation ex;
  for (const auto& l : loads) ex.profiles.emplace_back(l.profile);
  for (std::size_t i = 0; i < actuators.size(); ++i) ex.profiles.emplace_back(std::nullopt);
  return ex;
}

DesignError::DesignError(std::vector<std::string> problems)
    : std::runtime_error(join_lines(problems)), problems_(std::move(problems)) {}

Design parse_design(const std::string& text, const std::string& source) {
  if (text.size() > lim::kMaxFileBytes)
    throw DesignError({"design '" + source + "': " + std::to_string(text.size()) + " bytes; a design may be at most " +
                       std::to_string(lim::kMaxFileBytes) + " bytes (1 MiB)"});
  toml::table tbl;
  try {
    tbl = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << "design '" << source << "' line " << e.source().begin.line << ": not valid TOML: " << e.description();
    throw DesignError({os.str()});
  }
  Problems problems(source);
  Section root(&tbl, "", problems, 0);
  Design d;
  d.source = source;
  d.digest = 1469598103934665603ULL;  // FNV-1a 64
  for (unsigned char ch : text) d.digest = (d.digest ^ ch) * 1099511628211ULL;
  d.title = root.string("title", false).value_or(d.title);
  if (d.title.size() > lim::kMaxTitleBytes)  // it reaches every figure script and summary.json
    root.problem("title", "title is " + std::to_string(d.title.size()) + " bytes long; at most " +
                              std::to_string(lim::kMaxTitleBytes) + " (it is printed on every figure)");
  io_detail::read_model(root, d);
  io_detail::read_beam(root, d);
  Section out = root.table("output");
  d.plots = out.boolean("plots", false).value_or(d.plots);
  out.finish();
  Outputs outputs;
  outputs.fixed("every run", "summary.json");
  io_detail::read_free_vibration(root, d, outputs);
  const std::vector<std::string> rejected_actuators = io_detail::read_loads_and_actuators(root, d);
  io_detail::read_damping(root, d);
  io_detail::read_motion(root, d);
  io_detail::read_simulation(root, d, outputs);
  io_detail::read_maneuver(root, d, outputs, rejected_actuators);
  io_detail::read_controller(root, d, outputs, rejected_actuators);
  io_detail::read_bang_bang(root, d, outputs, problems, rejected_actuators);
  io_detail::read_sensors_lqg_sweep(root, d, outputs);
  io_detail::read_export(root, d, outputs);
  root.finish();
  outputs.check(problems);
  if (problems.empty()) {
    try {
      Beam check(d.beam);  // catches what only the whole beam can tell (mass centre off the beam)
    } catch (const std::invalid_argument& e) {
      problems.add(0, e.what());
    }
  }
  if (!problems.empty()) throw DesignError(problems.list());
  return d;
}

long long body_build_work(const Design& d) {
  const long long N = 3 + d.noa;
  const long long p = static_cast<long long>(d.beam.segments.size() + d.beam.point_masses.size());
  long long work = N * N * N * (15 + p) + 40 * (10 + d.noa) * p * p;
  // the finite-element basis solves its element model first: 4.2e-5 s of CPU an element-mode
  // at most (lim::kMaxBasisWork), about 12 000 units of 3.4 ns (a sweep sample's)
  if (d.basis.kind == BasisOptions::Kind::FiniteElement)
    work += 12000LL * d.basis.finite_element.elements * (d.noa + 2);
  return work;
}

Design load_design(const std::string& path) {
  namespace fs = std::filesystem;
  const std::string where = "design '" + path + "': ";
  const std::string cannot_open = where + "cannot open the file (does it exist and is it readable?)";
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);  // follows symbolic links
  if (ec || !fs::exists(status)) throw DesignError({cannot_open});
  if (fs::is_directory(status)) throw DesignError({where + "is a directory; give a design file (.toml)"});
  if (!fs::is_regular_file(status))
    throw DesignError({where + "is not a regular file (a device, pipe or socket); give a design file (.toml)"});
  const auto size = fs::file_size(path, ec);
  const std::string too_large = where + "is larger than " + std::to_string(lim::kMaxFileBytes) +
                                " bytes (1 MiB); a design file is a few kilobytes of TOML";
  if (!ec && size > lim::kMaxFileBytes) throw DesignError({too_large});
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DesignError({cannot_open});
  // Read in pieces until the end, stopping one piece past the limit (the file may have
  // grown since it was measured). Not into a buffer of the limit's size: zeroing 1 MiB cost
  // a thousand page faults' worth of time, 5% of a small design's whole run.
  std::string text;
  if (!ec) text.reserve(static_cast<std::size_t>(size));
  char piece[16384];
  do {
    in.read(piece, sizeof piece);
    text.append(piece, static_cast<std::size_t>(in.gcount()));
    if (text.size() > lim::kMaxFileBytes) throw DesignError({too_large});
  } while (in.good());
  if (in.bad()) throw DesignError({where + "cannot read the file"});
  return parse_design(text, path);
}

}  // namespace freeflex
