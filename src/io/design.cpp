#include "freeflex/io/design.hpp"

#include <fstream>
#include <sstream>

#include "design_reader.hpp"
#include "freeflex/model/basis.hpp"

namespace freeflex {
namespace {

using io_detail::Problems;
using io_detail::Range;
using io_detail::Section;

std::string join_lines(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& line : v) s += (s.empty() ? "" : "\n") + line;
  return s;
}

void read_beam(Section& root, Design& d) {
  Section b = root.table("beam");
  if (!b.present()) {
    b.problem("beam", "section [beam] is required");
    return;
  }
  BeamProperties& p = d.beam;
  auto segs = b.table_array("segment");
  const bool uniform_keys = b.has("length_m") || b.has("mass_kg") || b.has("mass_per_length_kg_m") ||
                            b.has("bending_stiffness_Nm2");
  if (!segs.empty() && uniform_keys) {
    b.problem("segment", "beam: give either length_m, mass and bending_stiffness_Nm2 (uniform) or "
                         "[[beam.segment]] tables (piecewise), not both");
  } else if (segs.empty()) {
    auto L = b.number("length_m", Range::positive(), true);
    std::optional<double> mass;
    if (b.has("mass_kg") && b.has("mass_per_length_kg_m")) {
      b.problem("mass_kg", "beam: give mass_kg or mass_per_length_kg_m, not both");
      b.number("mass_kg", Range::positive(), false);
      b.number("mass_per_length_kg_m", Range::positive(), false);
    } else if (b.has("mass_per_length_kg_m")) {
      auto mu = b.number("mass_per_length_kg_m", Range::positive(), true);
      if (mu && L) mass = *mu * *L;
    } else {
      mass = b.number("mass_kg", Range::positive(), true);
    }
    auto ei = b.number("bending_stiffness_Nm2", Range::positive(), true);
    if (L && mass && ei) p.segments.push_back({*L, *mass / *L, *ei});
  } else {
    bool ok = true;
    for (auto& s : segs) {
      auto L = s.number("length_m", Range::positive(), true);
      auto mu = s.number("mass_per_length_kg_m", Range::positive(), true);
      auto ei = s.number("bending_stiffness_Nm2", Range::positive(), true);
      s.finish();
      if (L && mu && ei) p.segments.push_back({*L, *mu, *ei});
      else ok = false;
    }
    if (!ok) p.segments.clear();
  }
  double length = 0.0;
  for (const auto& s : p.segments) length += s.length_m;
  const bool have_length = !p.segments.empty();
  const Range on_beam = have_length ? Range::closed(0.0, length) : Range::nonnegative();
  const Range inside = have_length ? Range{0.0, length, true, true} : Range::positive();

  if (b.has("reference_m")) p.reference_m = b.number("reference_m", inside, false);
  Section hub = b.table("hub");
  if (hub.present()) {
    p.hub_mass_kg = hub.number("mass_kg", Range::nonnegative(), false).value_or(0.0);
    p.hub_rotary_inertia_kgm2 = hub.number("rotary_inertia_kgm2", Range::nonnegative(), false).value_or(0.0);
    hub.finish();
  }
  for (auto& s : b.table_array("point_mass")) {
    auto pos = s.number("position_m", on_beam, true);
    auto m = s.number("mass_kg", Range::nonnegative(), true);
    s.finish();
    if (pos && m) p.point_masses.push_back({*pos, *m});
  }
  b.finish();
}

void read_free_vibration(Section& root, Design& d) {
  Section s = root.table("free_vibration");
  if (!s.present()) return;
  FreeVibrationStudy fv;
  if (auto v = s.integer_array("noa_sweep", 1, kMaxNoa, false)) fv.noa_sweep.assign(v->begin(), v->end());
  fv.modes = static_cast<int>(s.integer("modes", 1, kMaxNoa, false).value_or(4));
  fv.paper_table = s.boolean("paper_table", false).value_or(false);
  fv.table_name = s.string("table_name", false, true).value_or("frequencies");
  for (auto& m : s.table_array("mode_shape")) {
    ModeShapeRequest r;
    auto name = m.string("name", true, true);
    r.noa = static_cast<int>(m.integer("noa", 1, kMaxNoa, false).value_or(d.noa));
    auto mode = m.integer("mode", 1, r.noa, true);
    r.points = static_cast<int>(m.integer("points", 2, 100000, false).value_or(201));
    m.finish();
    if (name && mode) {
      r.name = *name;
      r.mode = static_cast<int>(*mode);
      fv.mode_shapes.push_back(r);
    }
  }
  s.finish();
  d.free_vibration = fv;
}

}  // namespace

DesignError::DesignError(std::vector<std::string> problems)
    : std::runtime_error(join_lines(problems)), problems_(std::move(problems)) {}

Design parse_design(const std::string& text, const std::string& source) {
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
  d.title = root.string("title", false).value_or("");
  Section model = root.table("model");
  d.noa = static_cast<int>(model.integer("noa", 1, kMaxNoa, false).value_or(6));
  model.finish();
  read_beam(root, d);
  Section out = root.table("output");
  d.plots = out.boolean("plots", false).value_or(true);
  out.finish();
  read_free_vibration(root, d);
  root.finish();
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

Design load_design(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DesignError({"design '" + path + "': cannot open the file (does it exist and is it readable?)"});
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_design(ss.str(), path);
}

}  // namespace freeflex
