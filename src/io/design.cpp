#include "freeflex/io/design.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "design_reader.hpp"
#include "freeflex/control/switch_time.hpp"
#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/model/basis.hpp"

namespace freeflex {
namespace {

using io_detail::plain_name;
using io_detail::Problems;
using io_detail::Range;
using io_detail::Section;
using io_detail::shortest;
namespace lim = design_limits;

/// Rows (or samples, grid points) that `span` gives at `step`, as the simulators count
/// them: ceil(span / step) steps plus the end point.
double count_of(double span, double step) { return std::ceil(span / step - 1e-9) + 1.0; }

/// A count for messages: whole digits while they are exact, else 3e+15.
std::string show_count(double n) {
  if (n < 1e15) return std::to_string(static_cast<long long>(n));
  return shortest(n);
}

/// Reports at `key` "LEAD with OTHER gives N WHAT; at most LIMIT: ADVICE" when `span`
/// at `step` gives more than `limit` points. LEAD names the reported key and its value
/// ("simulation.output_step_s = 1e-09"), OTHER the other one ("duration_s = 3").
bool check_count(Section& s, const std::string& key, const std::string& lead, const std::string& other, double span,
                 double step, const std::string& what, double limit, const std::string& advice) {
  const double n = count_of(span, step);
  if (n <= limit) return true;
  s.problem(key, lead + " with " + other + " gives " + show_count(n) + " " + what + "; at most " + show_count(limit) +
                     ": " + advice);
  return false;
}

/// `s` without surrounding blanks, in lower case (how Ipopt compares string option values).
std::string lower_trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
  std::string t = b == std::string::npos ? "" : s.substr(b, e - b + 1);
  for (char& ch : t) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return t;
}

/// Files the studies will write, so that two of them never share a name (one would
/// overwrite the other). A name comes from a design key or is fixed by a study.
class Outputs {
 public:
  /// Files `stem` + each extension, named by `key` of `s` (`given`: in the file, not a default).
  void named(const Section& s, const std::string& key, const std::string& stem, std::vector<std::string> exts) {
    Entry e;
    e.owner = s.key_path(key) + " = \"" + stem + "\"" + (s.has(key) ? "" : " (the default)");
    e.rank = s.has(key) ? 2 : 1;
    e.line = s.line(key);
    for (const auto& x : exts) e.files.push_back(stem + x);
    entries_.push_back(std::move(e));
  }
  /// A file whose name a study fixes.
  void fixed(const std::string& study, const std::string& file) { entries_.push_back({study, {file}, 0, 0}); }

  void check(Problems& problems) const {
    std::vector<const Entry*> order;
    for (const auto& e : entries_) order.push_back(&e);
    // fixed names first, then defaults, then names the file gives in file order: a clash
    // is reported at the key the user can change
    std::stable_sort(order.begin(), order.end(), [](const Entry* a, const Entry* b) {
      return a->rank != b->rank ? a->rank < b->rank : a->line < b->line;
    });
    for (std::size_t i = 0; i < order.size(); ++i) {
      if (order[i]->rank == 0) continue;
      for (std::size_t j = 0; j < i; ++j) {
        std::string shared;
        for (const auto& f : order[i]->files)
          if (std::find(order[j]->files.begin(), order[j]->files.end(), f) != order[j]->files.end())
            shared += (shared.empty() ? "" : ", ") + f;
        if (shared.empty()) continue;
        const Entry& other = *order[j];
        problems.add(order[i]->line, order[i]->owner + " writes " + shared + ", which " + other.owner +
                                         (other.rank == 2 ? " (line " + std::to_string(other.line) + ")" : "") +
                                         " writes too; output files must have distinct names");
        break;
      }
    }
  }

 private:
  struct Entry {
    std::string owner;
    std::vector<std::string> files;
    int rank = 0;  // 0 fixed by a study, 1 a default name, 2 given in the file
    int line = 0;
  };
  std::vector<Entry> entries_;
};

std::string join_lines(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& line : v) s += (s.empty() ? "" : "\n") + line;
  return s;
}

constexpr double kInf = std::numeric_limits<double>::infinity();
const Range kLength = Range::positive().supported(lim::kMinLength_m, lim::kMaxLength_m);
const Range kMass = Range::positive().supported(lim::kMinMass_kg, lim::kMaxMass_kg);
const Range kMassPerLength = Range::positive().supported(lim::kMinMassPerLength_kg_m, lim::kMaxMassPerLength_kg_m);
const Range kStiffness = Range::positive().supported(lim::kMinBendingStiffness_Nm2, lim::kMaxBendingStiffness_Nm2);
const Range kMassOrZero = Range::nonnegative().supported(-kInf, lim::kMaxMass_kg);
const Range kTime = Range::positive().supported(lim::kMinDuration_s, lim::kMaxTime_s);  // durations, horizons
const Range kWeight = Range::nonnegative().supported(-kInf, lim::kMaxWeight);
const Range kCommand = Range::positive().supported(-kInf, lim::kMaxCommand);  // limits, rate limits

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
    auto L = b.number("length_m", kLength, true);
    std::optional<double> mass;
    if (b.has("mass_kg") && b.has("mass_per_length_kg_m")) {
      b.problem("mass_kg", "beam: give mass_kg or mass_per_length_kg_m, not both");
      b.number("mass_kg", kMass, false);
      b.number("mass_per_length_kg_m", kMassPerLength, false);
    } else if (b.has("mass_per_length_kg_m")) {
      auto mu = b.number("mass_per_length_kg_m", kMassPerLength, true);
      if (mu && L) mass = *mu * *L;
    } else {
      mass = b.number("mass_kg", kMass, true);
    }
    auto ei = b.number("bending_stiffness_Nm2", kStiffness, true);
    if (L && mass && ei) p.segments.push_back({*L, *mass / *L, *ei});
  } else {
    bool ok = true;
    for (auto& s : segs) {
      auto L = s.number("length_m", kLength, true);
      auto mu = s.number("mass_per_length_kg_m", kMassPerLength, true);
      auto ei = s.number("bending_stiffness_Nm2", kStiffness, true);
      s.finish();
      if (L && mu && ei) p.segments.push_back({*L, *mu, *ei});
      else ok = false;
    }
    if (!ok) p.segments.clear();
    double total = 0.0;
    for (const auto& seg : p.segments) total += seg.length_m;
    if (total > lim::kMaxLength_m)
      b.problem("segment", "beam: the segments add up to " + shortest(total) + " m; at most " +
                               shortest(lim::kMaxLength_m) + " m");
  }
  double length = 0.0, total_mass = 0.0;
  for (const auto& s : p.segments) {
    length += s.length_m;
    total_mass += s.mass_per_length_kg_m * s.length_m;
  }
  // mass_kg is checked where it is given; a mass that comes from mass per length is checked here
  if (!p.segments.empty() && (!b.has("mass_kg") || !segs.empty()) &&
      (total_mass < lim::kMinMass_kg || total_mass > lim::kMaxMass_kg))
    b.problem(segs.empty() ? "mass_per_length_kg_m" : "segment",
              "beam: the mass per length gives a beam of " + shortest(total_mass) + " kg; it must be within [" +
                  shortest(lim::kMinMass_kg) + ", " + shortest(lim::kMaxMass_kg) + "] kg (the supported range)");
  const bool have_length = !p.segments.empty();
  const Range on_beam = have_length ? Range::closed(0.0, length) : Range::nonnegative();
  // o strictly inside, and not within L/1000 of an end: the full model's step count grows
  // like 1/distance^2 there, and at 1e-6 L its modes at rest can no longer be computed
  const Range inside =
      have_length ? Range{0.0, length, true, true}.supported(lim::kEndMargin * length, (1.0 - lim::kEndMargin) * length)
                  : Range::positive();

  if (b.has("reference_m")) p.reference_m = b.number("reference_m", inside, false);
  Section hub = b.table("hub");
  if (hub.present()) {
    p.hub_mass_kg = hub.number("mass_kg", kMassOrZero, false).value_or(0.0);
    p.hub_rotary_inertia_kgm2 =
        hub.number("rotary_inertia_kgm2", Range::nonnegative().supported(-kInf, lim::kMaxRotaryInertia_kgm2), false)
            .value_or(0.0);
    hub.finish();
  }
  for (auto& s : b.table_array("point_mass")) {
    auto pos = s.number("position_m", on_beam, true);
    auto m = s.number("mass_kg", kMassOrZero, true);
    s.finish();
    if (pos && m) p.point_masses.push_back({*pos, *m});
  }
  b.finish();
}

void read_free_vibration(Section& root, Design& d, Outputs& outputs) {
  Section s = root.table("free_vibration");
  if (!s.present()) return;
  FreeVibrationStudy fv;
  if (auto v = s.integer_array("noa_sweep", 1, kMaxNoa, false)) fv.noa_sweep.assign(v->begin(), v->end());
  fv.modes = static_cast<int>(s.integer("modes", 1, kMaxNoa, false).value_or(4));
  fv.paper_table = s.boolean("paper_table", false).value_or(false);
  fv.table_name = s.string("table_name", false, true).value_or("frequencies");
  outputs.named(s, "table_name", fv.table_name, {".csv"});
  for (auto& m : s.table_array("mode_shape")) {
    ModeShapeRequest r;
    auto name = m.string("name", true, true);
    r.noa = static_cast<int>(m.integer("noa", 1, kMaxNoa, false).value_or(d.noa));
    auto mode = m.integer("mode", 1, r.noa, true);
    r.points = static_cast<int>(m.integer("points", 2, 100000, false).value_or(201));
    m.finish();
    if (name) outputs.named(m, "name", *name, {".csv", ".gp", ".png"});
    if (name && mode) {
      r.name = *name;
      r.mode = static_cast<int>(*mode);
      fv.mode_shapes.push_back(r);
    }
  }
  s.finish();
  d.free_vibration = fv;
}

std::optional<ForceElement> read_element(Section& s, double length, bool& ok, std::string& name_read) {
  ForceElement e;
  auto name = s.string("name", true, true);
  if (name) name_read = *name;
  auto type = s.choice("type", {"force", "thruster", "torque"}, true);
  const Range on_beam = length > 0 ? Range::closed(0.0, length) : Range::nonnegative();
  auto pos = s.number("position_m", on_beam, true);
  if (type && *type == "torque") {
    if (s.has("direction")) s.problem("direction", s.key_path("direction") + " does not apply to a torque");
    if (s.has("follow_slope")) s.problem("follow_slope", s.key_path("follow_slope") + " applies to thrusters only");
    s.number_array("direction", Range(), false);
    s.boolean("follow_slope", false);
  } else {
    const auto dir = s.number_array("direction", Range().supported(-lim::kMaxDirection, lim::kMaxDirection), true);
    if (dir && dir->size() == 2) {
      e.direction = Eigen::Vector2d((*dir)[0], (*dir)[1]);
      const double norm = e.direction.norm();
      if (!(norm >= lim::kMinDirection && norm <= lim::kMaxDirection)) {
        s.problem("direction", s.key_path("direction") + " = [" + shortest((*dir)[0]) + ", " + shortest((*dir)[1]) +
                                   "] has length " + shortest(norm) + ", must have a length in [" +
                                   shortest(lim::kMinDirection) + ", " + shortest(lim::kMaxDirection) +
                                   "] (it is the force per unit command)");
        ok = false;
      }
    } else {
      if (dir)
        s.problem("direction", s.key_path("direction") + " must have two components [x, y], got " +
                                   std::to_string(dir->size()));
      ok = false;
    }
    if (type && *type == "force" && s.has("follow_slope"))
      s.problem("follow_slope", s.key_path("follow_slope") + " applies to thrusters only");
    e.follow_slope = s.boolean("follow_slope", false).value_or(false);
  }
  if (!name || !type || !pos) {
    ok = false;
    return std::nullopt;
  }
  e.name = *name;
  e.type = *type == "force" ? ForceElement::Type::Force
           : *type == "thruster" ? ForceElement::Type::Thruster
                                 : ForceElement::Type::Torque;
  e.position_m = *pos;
  return e;
}

std::optional<TimeProfile> read_profile(Section& load) {
  Section p = load.table("profile");
  if (!p.present()) {
    load.problem("profile", load.key_path("profile") + " is required ([" + load.path().substr(0, load.path().find('[')) +
                                ".profile] with type, times_s, values)");
    return std::nullopt;
  }
  auto type = p.choice("type", {"steps", "linear"}, true);
  auto times = p.number_array("times_s", Range::nonnegative().supported(-kInf, lim::kMaxTime_s), true);
  auto values = p.number_array("values", Range().supported(-lim::kMaxCommand, lim::kMaxCommand), true);
  p.finish();
  if (!type || !times || !values) return std::nullopt;
  for (std::size_t i = 1; i < times->size(); ++i)
    if (!((*times)[i] > (*times)[i - 1])) {
      std::ostringstream os;
      os << p.key_path("times_s") << " must be strictly increasing: entry " << i + 1 << " (" << shortest((*times)[i])
         << ") does not exceed entry " << i << " (" << shortest((*times)[i - 1]) << ")";
      p.problem("times_s", os.str());
      return std::nullopt;
    }
  if (times->size() < 2) {
    p.problem("times_s", p.key_path("times_s") + " needs at least two times");
    return std::nullopt;
  }
  const bool steps = *type == "steps";
  const std::size_t expect = steps ? times->size() - 1 : times->size();
  if (values->size() != expect) {
    p.problem("values", p.key_path("values") + " has " + std::to_string(values->size()) + " entries, must have " +
                            std::to_string(expect) + (steps ? " (one per interval between times_s)" : " (one per time)"));
    return std::nullopt;
  }
  return TimeProfile(steps ? TimeProfile::Kind::Steps : TimeProfile::Kind::Linear, *times, *values);
}

double beam_length(const Design& d) {
  double L = 0.0;
  for (const auto& s : d.beam.segments) L += s.length_m;
  return L;
}

/// Returns the names of the actuators rejected for a bad field (already reported), so that
/// the sections naming them do not report them again as unknown.
std::vector<std::string> read_loads_and_actuators(Section& root, Design& d) {
  const double L = beam_length(d);
  std::vector<std::string> seen, rejected;
  auto check_name = [&](const std::string& name, Section& s) {
    if (name.empty()) return;  // missing or not a string: reported by read_element
    if (std::find(seen.begin(), seen.end(), name) != seen.end())
      s.problem("name", s.key_path("name") + " = \"" + name + "\" is used twice; load and actuator names must be unique");
    seen.push_back(name);
  };
  for (auto& s : root.table_array("load")) {
    bool ok = true;
    std::string name;
    auto e = read_element(s, L, ok, name);
    auto prof = read_profile(s);
    s.finish();
    check_name(name, s);
    if (e && ok && prof) d.loads.push_back({*e, *prof});
  }
  for (auto& s : root.table_array("actuator")) {
    bool ok = true;
    std::string name;
    auto e = read_element(s, L, ok, name);
    const auto limit = s.number("limit", kCommand, false);
    s.finish();
    check_name(name, s);
    if (e && ok && (limit || !s.has("limit"))) d.actuators.push_back({*e, limit.value_or(0.0)});
    else if (!name.empty()) rejected.push_back(name);
  }
  return rejected;
}

void read_damping(Section& root, Design& d) {
  Section s = root.table("damping");
  if (!s.present()) return;
  if (auto r = s.number_array("ratios", Range{0.0, 1.0, false, true}, true)) {
    if (static_cast<int>(r->size()) > d.noa)
      s.problem("ratios", s.key_path("ratios") + " has " + std::to_string(r->size()) + " entries, but the model has " +
                              std::to_string(d.noa) + " elastic modes (model.noa = " + std::to_string(d.noa) +
                              "); at most " + std::to_string(d.noa));
    else
      d.damping_ratios = *r;
  }
  s.finish();
}

/// The latest time any load acts (0 without loads).
double loads_end(const Design& d) {
  double end = 0.0;
  for (const auto& l : d.loads) end = std::max(end, l.profile.times().back());
  return end;
}

void read_simulation(Section& root, Design& d, Outputs& outputs) {
  Section s = root.table("simulation");
  if (!s.present()) return;
  SimulationStudy st;
  SimulationOptions& o = st.options;
  auto dur = s.number("duration_s", kTime, true);
  if (dur) o.duration_s = *dur;
  auto step = s.number("output_step_s", Range::positive(), false);
  o.output_step_s = step.value_or(o.duration_s / 600.0);
  if (dur && step) {
    if (*step > *dur)
      s.problem("output_step_s", s.key_path("output_step_s") + " = " + shortest(*step) +
                                     " exceeds duration_s = " + shortest(*dur) + "; it must not");
    else
      check_count(s, "output_step_s", s.key_path("output_step_s") + " = " + shortest(*step),
                  "duration_s = " + shortest(*dur), *dur, *step, "output rows", lim::kMaxOutputRows,
                  "raise output_step_s or shorten duration_s");
  }
  auto traj = s.number("trajectory_step_s", Range::positive(), false);
  o.trajectory_step_s = traj.value_or(o.trajectory_step_s);
  o.integrator.rtol = s.number("rtol", Range{0.0, 1.0, true, true}, false).value_or(1e-8);
  // an absolute error of 1 (m, rad, modal amplitude) or more would switch the error control off
  o.integrator.atol = s.number("atol", Range{0.0, 1.0, true, true}, false).value_or(1e-10);
  o.integrator.max_step = s.number("max_step_s", Range::nonnegative(), false).value_or(0.0);
  const std::string method = s.choice("method", {"bdf", "adams"}, false).value_or("adams");
  o.integrator.method = method == "adams" ? IntegratorOptions::Method::Adams : IntegratorOptions::Method::Bdf;
  auto variables = [&s](const char* key, const char* fallback) {
    return s.choice(key, {"modal", "physical"}, false).value_or(fallback) == "modal"
               ? SimulationOptions::Variables::Modal
               : SimulationOptions::Variables::Physical;
  };
  o.full_variables = variables("full_model_variables", "physical");
  o.first_order_variables = variables("first_order_variables", "modal");
  st.nonlinear = s.boolean("nonlinear", false).value_or(true);
  st.perturbation = s.boolean("perturbation", false).value_or(true);
  // the perturbation solution samples the zero-order motion at the finer of the two steps
  // (the output rows are bounded above)
  if (st.perturbation && !root.has("maneuver") && dur && (step || !s.has("output_step_s")) &&
      (traj || !s.has("trajectory_step_s")) && o.trajectory_step_s < o.output_step_s)
    check_count(s, traj ? "trajectory_step_s" : "duration_s",
                traj ? s.key_path("trajectory_step_s") + " = " + shortest(o.trajectory_step_s)
                     : s.key_path("duration_s") + " = " + shortest(*dur),
                traj ? "duration_s = " + shortest(*dur)
                     : "trajectory_step_s = " + shortest(o.trajectory_step_s) + " (the default)",
                *dur, o.trajectory_step_s, "samples of the zero-order motion", lim::kMaxTrajectorySamples,
                "raise trajectory_step_s or shorten duration_s");
  if (!st.nonlinear && !st.perturbation)
    s.problem("nonlinear", s.key_path("nonlinear") + " and perturbation are both false: nothing to simulate");
  if (auto name = s.string("rigid_figure", false, true)) st.rigid_figure = *name;
  if (auto name = s.string("elastic_figure", false, true)) st.elastic_figure = *name;
  s.finish();
  outputs.named(s, "rigid_figure", st.rigid_figure, {".gp", ".png"});
  outputs.named(s, "elastic_figure", st.elastic_figure, {".gp", ".png"});
  if (st.nonlinear) outputs.fixed("[simulation]", "nonlinear.csv");
  if (st.perturbation) outputs.fixed("[simulation]", "perturbation.csv");
  // a [[load]] that has problems of its own is not missing as well
  if (!root.has("load") && !root.has("maneuver"))
    s.problem("duration_s", "[simulation] needs at least one [[load]] or a [maneuver] to respond to");
  if (dur && !d.loads.empty() && !root.has("maneuver")) {
    double first = std::numeric_limits<double>::infinity();
    for (const auto& l : d.loads) first = std::min(first, l.profile.times().front());
    if (first >= *dur)
      s.problem("duration_s", s.key_path("duration_s") + " = " + shortest(*dur) +
                                  " ends before any load acts (the first at " + shortest(first) +
                                  " s): nothing would move");
  }
  d.simulation = st;
}

/// Resolves [[actuator]] names to element indices (loads come first in force_elements()).
/// Names in `rejected` (actuators with a bad field, already reported) are left out silently.
std::vector<int> actuator_indices(Section& s, const std::string& key, const std::vector<std::string>& names,
                                  const Design& d, const std::vector<std::string>& rejected) {
  std::vector<int> idx;
  for (std::size_t k = 0; k < names.size(); ++k) {
    const std::string& name = names[k];
    const auto first = std::find(names.begin(), names.end(), name) - names.begin();
    if (first < static_cast<std::ptrdiff_t>(k)) {
      if (std::find(names.begin() + first + 1, names.end(), name) - names.begin() == static_cast<std::ptrdiff_t>(k))
        s.problem(key, s.key_path(key) + " lists \"" + name + "\" more than once; each actuator at most once");
      continue;
    }
    int found = -1;
    for (std::size_t i = 0; i < d.actuators.size(); ++i)
      if (d.actuators[i].element.name == name) found = static_cast<int>(i);
    if (found < 0 && std::find(rejected.begin(), rejected.end(), name) != rejected.end()) continue;
    if (found < 0) {
      std::string known;
      for (const auto& a : d.actuators) known += (known.empty() ? "'" : ", '") + a.element.name + "'";
      s.problem(key, s.key_path(key) + ": \"" + name + "\" is not an [[actuator]] (known: " +
                         (known.empty() ? "none" : known) + ")");
      continue;
    }
    idx.push_back(static_cast<int>(d.loads.size()) + found);
  }
  return idx;
}

/// [maneuver.initial] / [maneuver.final]: position_m, theta_deg, velocity_m_s, theta_rate_deg_s.
Eigen::Matrix<double, 6, 1> read_state(Section& m, const std::string& key) {
  Eigen::Matrix<double, 6, 1> x = Eigen::Matrix<double, 6, 1>::Zero();
  Section s = m.table(key);
  if (!s.present()) return x;
  auto pair = [&](const std::string& k, int at, double bound) {
    auto v = s.number_array(k, Range().supported(-bound, bound), false);
    if (!v) return;
    if (v->size() != 2) {
      s.problem(k, s.key_path(k) + " must have two components [x, y], got " + std::to_string(v->size()));
      return;
    }
    x(at) = (*v)[0];
    x(at + 1) = (*v)[1];
  };
  pair("position_m", 0, lim::kMaxPosition_m);
  pair("velocity_m_s", 3, lim::kMaxVelocity_m_s);
  // degrees only in files
  x(2) = s.number("theta_deg", Range().supported(-lim::kMaxAngle_deg, lim::kMaxAngle_deg), false).value_or(0.0) * M_PI /
         180.0;
  x(5) =
      s.number("theta_rate_deg_s", Range().supported(-lim::kMaxRate_deg_s, lim::kMaxRate_deg_s), false).value_or(0.0) *
      M_PI / 180.0;
  s.finish();
  return x;
}

void read_maneuver(Section& root, Design& d, Outputs& outputs, const std::vector<std::string>& rejected) {
  Section m = root.table("maneuver");
  if (!m.present()) return;
  ManeuverStudy st;
  ManeuverProblem& p = st.problem;
  TrajoptOptions& o = st.options;
  // actuators by name, with their limits as bounds
  bool names_ok = false;  // else the per-actuator sizes below are not checked
  if (auto list = m.string_array("actuators", true)) {
    p.actuators = actuator_indices(m, "actuators", *list, d, rejected);
    names_ok = p.actuators.size() == list->size();
    std::vector<double> lo, hi;
    for (int e : p.actuators) {
      const ActuatorSpec& a = d.actuators[static_cast<std::size_t>(e) - d.loads.size()];
      st.actuator_names.push_back(a.element.name);
      lo.push_back(a.limit > 0 ? -a.limit : -ManeuverProblem::inf);
      hi.push_back(a.limit > 0 ? a.limit : ManeuverProblem::inf);
    }
    p.u_min = Eigen::Map<Eigen::VectorXd>(lo.data(), static_cast<Eigen::Index>(lo.size()));
    p.u_max = Eigen::Map<Eigen::VectorXd>(hi.data(), static_cast<Eigen::Index>(hi.size()));
  }
  const std::size_t nu = p.actuators.size();
  p.x_initial = read_state(m, "initial");
  p.x_final = read_state(m, "final");
  const std::string objective =
      m.choice("objective", {"energy", "time", "smooth", "weighted"}, false).value_or("energy");
  const bool time_objective = objective == "time" || (objective == "weighted" && m.has("time_weight"));
  p.free_time = m.boolean("free_duration", false).value_or(time_objective);
  if (objective == "time" && !p.free_time)
    m.problem("free_duration", m.key_path("free_duration") + " = false, but objective \"time\" needs a free duration");
  // A value given but rejected (its problem is reported) reads as NaN, so that the checks
  // of other sections against it stay silent instead of quoting a default the file lacks.
  auto duration = [&](const char* key, bool required, double fallback) {
    const auto v = m.number(key, kTime, required);
    return v ? *v : (m.has(key) || required ? std::numeric_limits<double>::quiet_NaN() : fallback);
  };
  p.t_min_s = duration("duration_min_s", false, 0.1);
  p.t_max_s = duration("duration_max_s", false, 10.0);
  p.duration_s = duration("duration_s", !p.free_time, 0.5 * (p.t_min_s + p.t_max_s));
  if (p.free_time && p.t_min_s > p.t_max_s)
    m.problem("duration_min_s", m.key_path("duration_min_s") + " must not exceed duration_max_s");
  p.w_energy = objective == "energy" ? 1.0 : 0.0;
  p.w_time = objective == "time" ? 1.0 : 0.0;
  p.w_smooth = objective == "smooth" ? 1.0 : 0.0;
  if (objective == "weighted") {
    p.w_energy = m.number("energy_weight", kWeight, false).value_or(0.0);
    p.w_time = m.number("time_weight", kWeight, false).value_or(0.0);
    p.w_smooth = m.number("smooth_weight", kWeight, false).value_or(0.0);
    if (p.w_energy + p.w_time + p.w_smooth <= 0.0)
      m.problem("objective", m.key_path("objective") + " = \"weighted\" needs energy_weight, time_weight or "
                                                        "smooth_weight > 0");
  } else {
    for (const char* k : {"energy_weight", "time_weight", "smooth_weight"})
      if (m.has(k)) m.problem(k, m.key_path(k) + " applies to objective = \"weighted\" only");
    for (const char* k : {"energy_weight", "time_weight", "smooth_weight"}) m.number(k, Range(), false);
  }
  if (time_objective && !p.free_time && p.w_time > 0.0)
    m.problem("time_weight", m.key_path("time_weight") + " > 0 needs free_duration = true");
  // An optional array with one entry per actuator, into `target`.
  auto per_actuator = [&](const char* key, const Range& range, auto& target) {
    auto v = m.number_array(key, range, false);
    if (!v) return;
    if (v->size() == nu)
      target = Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v->data(), static_cast<Eigen::Index>(v->size())));
    else if (names_ok)
      m.problem(key, m.key_path(key) + " needs one entry per actuator (" + std::to_string(nu) + ")");
  };
  per_actuator("actuator_weights", kWeight, p.energy_weights);
  per_actuator("rate_limits", kCommand, p.du_max);
  const std::string tr =
      m.choice("transcription", {"hermite_simpson", "hermite_simpson_compressed", "trapezoidal"}, false)
          .value_or("hermite_simpson");
  o.transcription = tr == "trapezoidal"                  ? Transcription::Trapezoidal
                    : tr == "hermite_simpson_compressed" ? Transcription::HermiteSimpsonCompressed
                                                         : Transcription::HermiteSimpson;
  o.intervals = static_cast<int>(m.integer("intervals", 1, lim::kMaxIntervals, false).value_or(100));
  o.mesh_refinements = static_cast<int>(m.integer("mesh_refinements", 0, 20, false).value_or(0));
  o.mesh_tolerance = m.number("mesh_tolerance", Range::positive(), false).value_or(1e-6);
  o.tol = m.number("tolerance", Range{0.0, 1.0, true, true}, false).value_or(1e-8);
  o.max_iter = static_cast<int>(m.integer("max_iterations", 1, 1000000, false).value_or(3000));
  o.verbose = !m.boolean("quiet", false).value_or(false);
  Section ip = m.table("ipopt");
  if (ip.present()) {
    for (const auto& [key, value] : ip.raw_entries()) {
      // Debian's Ipopt is built with MUMPS only: any other solver makes Ipopt abort the
      // whole process (it tries to load libhsl.so)
      if (key == "linear_solver" && lower_trimmed(value) != "mumps") {
        ip.problem(
            key, ip.key_path(key) + " = \"" + value + "\", must be \"mumps\" (the only linear solver this Ipopt has)");
        continue;
      }
      if (key == "linear_system_scaling" && lower_trimmed(value) == "mc19") {
        ip.problem(key, ip.key_path(key) + " = \"" + value +
                            "\", must be \"none\" or \"slack-based\" (MC19 is part of HSL, which this Ipopt lacks)");
        continue;
      }
      // freeflex writes Ipopt's log there, into the run's directory with the other results
      // (and replaced with them), so it must be a plain file name.
      if (key == "output_file") {
        if (!plain_name(value, ".")) {
          ip.problem(key, ip.key_path(key) + " = \"" + value +
                              "\", must be a file name of 1 to 64 letters, digits, '_', '-' or '.', not starting with "
                              "'.' (Ipopt writes it into the output directory)");
          continue;
        }
        outputs.named(ip, key, value, {""});
      }
      o.ipopt_options.emplace_back(key, value);
    }
  }
  m.finish();
  outputs.fixed("[maneuver]", "trajectory.csv");
  for (const char* f : {"maneuver_states.gp", "maneuver_states.png", "maneuver_controls.gp", "maneuver_controls.png"})
    outputs.fixed("[maneuver]", f);
  d.maneuver = st;
}

void read_controller(Section& root, Design& d, Outputs& outputs, const std::vector<std::string>& rejected) {
  Section c = root.table("controller");
  if (!c.present()) return;
  ControllerStudy st;
  c.choice("type", {"tvlqr"}, false);
  bool names_ok = false;  // else the per-actuator sizes below are not checked
  if (auto names = c.string_array("actuators", true)) {
    st.actuators = actuator_indices(c, "actuators", *names, d, rejected);
    names_ok = st.actuators.size() == names->size();
    if (names_ok) st.actuator_names = *names;
  }
  const std::size_t m = st.actuators.size();
  st.limits.resize(static_cast<Eigen::Index>(m));
  for (std::size_t k = 0; k < m; ++k) {
    const double lim = d.actuators[st.actuators[k] - d.loads.size()].limit;
    st.limits(static_cast<Eigen::Index>(k)) = lim > 0 ? lim : std::numeric_limits<double>::infinity();
  }
  auto horizon = c.number("horizon_s", kTime, true);
  st.horizon_s = horizon.value_or(st.horizon_s);
  auto state_weight = [&](const char* key) {
    const double w = c.number(key, Range().supported(-lim::kMaxWeight, lim::kMaxWeight), false).value_or(1.0);
    if (w < 0.0) {
      c.problem(key, c.key_path(key) + " = " + shortest(w) +
                         ", must be >= 0 (the state weight Q must be positive semidefinite)");
      return 0.0;
    }
    return w;
  };
  st.weight_elastic = state_weight("weight_elastic");
  st.weight_rigid_position = state_weight("weight_rigid_position");
  st.weight_rigid_rate = state_weight("weight_rigid_rate");
  st.input_weights = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(m));
  if (c.has("input_weights")) {
    auto w = c.number_array("input_weights", Range().supported(-lim::kMaxWeight, lim::kMaxWeight), false);
    if (w) {  // else reported by number_array, which returns no empty array
      const auto [lo, hi] = std::minmax_element(w->begin(), w->end());
      if (!(*lo > 0.0)) {
        c.problem("input_weights", c.key_path("input_weights") +
                                       ": every entry must be > 0 (the input weight R must be positive definite)");
      } else if (*lo < lim::kMinInputWeight) {
        c.problem("input_weights", c.key_path("input_weights") + ": every entry must be in [" +
                                       shortest(lim::kMinInputWeight) + ", " + shortest(lim::kMaxWeight) + "]");
      } else if (*hi > lim::kMaxInputWeightSpread * *lo) {
        c.problem("input_weights", c.key_path("input_weights") + " spans " + shortest(*lo) + " to " + shortest(*hi) +
                                       ", more than a factor " + shortest(lim::kMaxInputWeightSpread) +
                                       " (R would be numerically singular); rescale the actuators' commands instead");
      } else if (w->size() != m) {
        if (names_ok)
          c.problem("input_weights",
                    c.key_path("input_weights") + " needs one entry per actuator (" + std::to_string(m) + ")");
      } else {
        st.input_weights = Eigen::Map<const Eigen::VectorXd>(w->data(), static_cast<Eigen::Index>(m));
      }
    }
  }
  if (st.weight_elastic + st.weight_rigid_position + st.weight_rigid_rate <= 0.0)
    c.problem("weight_elastic", "controller: every state weight is zero; Q must weight something");
  auto grid = c.number("grid_step_s", Range::positive(), false);
  st.grid_step_s = grid.value_or(st.grid_step_s);
  if (horizon && (grid || !c.has("grid_step_s")))
    check_count(
        c, grid ? "grid_step_s" : "horizon_s",
        grid ? c.key_path("grid_step_s") + " = " + shortest(*grid)
             : c.key_path("horizon_s") + " = " + shortest(*horizon),
        grid ? "horizon_s = " + shortest(*horizon) : "grid_step_s = " + shortest(st.grid_step_s) + " (the default)",
        *horizon, st.grid_step_s, "TV-LQR gain grid points", lim::kMaxOutputRows,
        "raise grid_step_s or shorten horizon_s");
  auto until = c.number("simulate_until_s", kTime, false);
  st.simulate_until_s = until.value_or(st.horizon_s);
  if (auto name = c.string("figure", false, true)) st.figure = *name;
  c.finish();
  outputs.named(c, "figure", st.figure, {".gp", ".png"});
  outputs.fixed("[controller]", "comparison.csv");
  for (const char* cs : {"open_loop", "tvlqr"})
    for (const char* model : {"first_order", "nonlinear"})
      outputs.fixed("[controller]", std::string("case_") + cs + "_" + model + ".csv");
  if (!root.has("load") && !root.has("maneuver"))
    c.problem("actuators",
              "[controller] needs a nominal motion whose vibration it suppresses: add a [[load]] or a "
              "[maneuver]");
  if (d.maneuver && horizon) {
    const ManeuverProblem& p = d.maneuver->problem;
    const double shortest_maneuver = p.free_time ? p.t_min_s : p.duration_s;
    if (st.horizon_s < shortest_maneuver)
      c.problem("horizon_s", c.key_path("horizon_s") + " = " + shortest(st.horizon_s) + ", shorter than the maneuver (" +
                                 (p.free_time ? "maneuver.duration_min_s = " : "maneuver.duration_s = ") +
                                 shortest(shortest_maneuver) + ")");
  }
  if (!d.loads.empty() && !d.maneuver) {
    const double end = loads_end(d);
    if (horizon && st.horizon_s < end)
      c.problem("horizon_s", c.key_path("horizon_s") + " = " + shortest(st.horizon_s) +
                                 ", shorter than the maneuver (its loads act until " + shortest(end) + " s)");
  }
  // The comparison runs: from 0 to simulate_until_s, at the [simulation] output and
  // trajectory steps (or 0.005 s and the default 0.001 s without one).
  const bool have_end = until || (!c.has("simulate_until_s") && horizon);
  if (have_end) {
    const std::string end_key = until ? "simulate_until_s" : "horizon_s";
    const std::string end_text = until ? c.key_path("simulate_until_s") : "controller.simulate_until_s (= horizon_s)";
    const double t_end = st.simulate_until_s;
    const bool from_simulation = d.simulation.has_value();
    const double out_step = from_simulation ? d.simulation->options.output_step_s : 0.005;
    const double traj_step =
        from_simulation ? d.simulation->options.trajectory_step_s : SimulationOptions{}.trajectory_step_s;
    const std::string out_text =
        from_simulation ? "simulation.output_step_s" : "the fixed output step (no [simulation])";
    if (until && horizon && !d.maneuver && t_end < st.horizon_s)
      c.problem("simulate_until_s", c.key_path("simulate_until_s") + " = " + shortest(t_end) +
                                        " is shorter than horizon_s = " + shortest(st.horizon_s) +
                                        " (without a [maneuver] the nominal motion is "
                                        "computed up to simulate_until_s, and the TV-LQR needs it over the horizon)");
    else if (out_step > t_end)
      c.problem(end_key, end_text + " = " + shortest(t_end) + " is shorter than " + out_text + " = " +
                             shortest(out_step) + "; it must not be");
    else if (check_count(c, end_key, end_text + " = " + shortest(t_end), out_text + " = " + shortest(out_step), t_end,
                         out_step, "output rows of the comparison runs", lim::kMaxOutputRows,
                         from_simulation ? "shorten simulate_until_s or raise simulation.output_step_s"
                                         : "shorten simulate_until_s") &&
             traj_step < out_step)
      check_count(
          c, end_key, end_text + " = " + shortest(t_end),
          (from_simulation ? "simulation.trajectory_step_s = " : "the default trajectory step ") + shortest(traj_step),
          t_end, traj_step, "samples of the zero-order motion", lim::kMaxTrajectorySamples,
          "shorten simulate_until_s or raise [simulation] trajectory_step_s");
  }
  if (d.maneuver) {
    for (int a : d.maneuver->problem.actuators)
      if (std::find(st.actuators.begin(), st.actuators.end(), a) == st.actuators.end())
        c.problem("actuators", c.key_path("actuators") + " must include every maneuver actuator (the feedback adds "
                                                         "to their commands); \"" +
                                   d.actuators[a - d.loads.size()].element.name + "\" is missing");
  }
  d.controller = st;
}


/// ∫_0^T (T - s) v(s) ds for a load profile (zero outside its times): I_o θ(T) for a
/// moment M(s) = v(s) from rest.
double rotation_integral(const TimeProfile& prof, double T) {
  const auto& t = prof.times();
  const auto& v = prof.values();
  const bool steps = prof.kind() == TimeProfile::Kind::Steps;
  double sum = 0.0;
  for (std::size_t i = 0; i + 1 < t.size(); ++i) {
    const double a = std::max(0.0, t[i]), b = std::min(T, t[i + 1]);
    if (!(b > a)) continue;
    auto value = [&](double x) {  // on [t_i, t_i+1]
      if (steps) return v[i];
      const double w = (x - t[i]) / (t[i + 1] - t[i]);
      return (1.0 - w) * v[i] + w * v[i + 1];
    };
    const double m = 0.5 * (a + b);  // Simpson: exact for the quadratic integrand
    sum += (b - a) / 6.0 * ((T - a) * value(a) + 4.0 * (T - m) * value(m) + (T - b) * value(b));
  }
  return sum;
}

/// What only the discretized body can tell about [bang_bang]: the torque acts at o, o is
/// the mass centre, the k values are modes the torque excites, and the nominal motion turns
/// the beam by a positive angle (design_switch_times needs Δθ > 0).
void check_bang_bang_body(Section& b, const Design& d) {
  const BangBangStudy& st = *d.bang_bang;
  const FlexibleBody body(Beam(d.beam), d.noa, d.force_elements(), d.damping_ratios);
  const double L = body.beam().length();
  const ModalIntegrals& mi = body.integrals();
  const ActuatorSpec& a = d.actuators[static_cast<std::size_t>(st.actuator) - d.loads.size()];
  const double s_o = body.beam().reference_s();
  if (std::abs(body.element_x(st.actuator)) > 1e-9 * L) {
    b.problem("actuator", b.key_path("actuator") + ": \"" + st.actuator_name +
                              "\" acts at position_m = " + shortest(a.element.position_m) + ", but o is at " +
                              shortest(s_o) + " m from the left end; the bang-bang torque must act at o");
    return;
  }
  if (std::abs(mi.S_o) > 1e-9 * mi.m * L) {
    b.problem("actuator", "[bang_bang] needs o at the mass centre (" + shortest(s_o + mi.S_o / mi.m) +
                              " m from the left end), but beam.reference_m puts it at " + shortest(s_o) + " m");
    return;
  }
  const int excited = static_cast<int>(excited_modes(body, st.actuator).excited.size());
  for (int k : st.modes)
    if (k > excited) {
      b.problem("modes", b.key_path("modes") + " contains " + std::to_string(k) + ", but \"" + st.actuator_name +
                             "\" excites only " + std::to_string(excited) +
                             " elastic modes with model.noa = " + std::to_string(d.noa) + "; each k must be at most " +
                             std::to_string(excited) + " (a larger noa may excite more)");
      break;
    }
  // The rotation the bang-bang flies: the nominal motion's angle at simulate_until_s.
  if (d.maneuver) {
    const ManeuverProblem& p = d.maneuver->problem;
    if (p.x_final(5) == 0.0 && !(p.x_final(2) > 0.0))
      b.problem("actuator",
                "[bang_bang] flies the nominal rotation, but the maneuver ends at rest at "
                "maneuver.final.theta_deg = " +
                    shortest(p.x_final(2) * 180.0 / M_PI) + "; bang-bang rotations need a positive angle");
    return;
  }
  if (!d.controller) return;
  const double T = d.controller->simulate_until_s;
  const int N = body.dofs();
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(body.n());
  Eigen::VectorXd g(N);
  bool turns = false, known = true;  // known: every moment is independent of the attitude
  double rotation = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < d.loads.size(); ++i) {
    const LoadSpec& l = d.loads[i];
    bool zero = true;
    for (double v : l.profile.values()) zero = zero && v == 0.0;
    if (zero) continue;
    body.element_force(static_cast<int>(i), 0.0, q0, g);  // g(2): moment about o per unit command at rest
    const bool torque = l.element.type == ForceElement::Type::Torque;
    const double arm = torque ? 1.0 : std::abs(g(2)) / l.element.direction.norm();
    if (!torque && !(arm > 1e-9 * L)) continue;  // through o or along the beam: no moment at theta = 0
    turns = true;
    if (l.element.type == ForceElement::Type::Force) known = false;  // inertial direction: moment depends on theta
    const double r = g(2) * rotation_integral(l.profile, T);
    rotation += r;
    scale += std::abs(r);
  }
  if (!turns) {
    b.problem("actuator",
              "[bang_bang] flies the nominal rotation, but no [[load]] turns the beam (each is zero, acts "
              "through o or along the beam): the rotation would be 0");
  } else if (known && !(rotation > 1e-9 * scale)) {
    b.problem("actuator", "[bang_bang] flies the nominal rotation, but the loads turn the beam by " +
                              std::string(rotation < -1e-9 * scale ? "a negative angle" : "0 rad") +
                              " by controller.simulate_until_s = " + shortest(T) +
                              " s; bang-bang rotations need a positive angle");
  }
}

void read_bang_bang(Section& root, Design& d, Outputs& outputs, const Problems& problems,
                    const std::vector<std::string>& rejected) {
  Section b = root.table("bang_bang");
  if (!b.present()) return;
  BangBangStudy st;
  bool actuator_ok = false;
  if (auto name = b.string("actuator", true)) {
    const auto idx = actuator_indices(b, "actuator", {*name}, d, rejected);
    if (!idx.empty()) {
      st.actuator = idx[0];
      st.actuator_name = *name;
      const ActuatorSpec& a = d.actuators[static_cast<std::size_t>(idx[0]) - d.loads.size()];
      actuator_ok = true;
      if (a.element.type != ForceElement::Type::Torque) {
        b.problem("actuator", b.key_path("actuator") + ": \"" + *name + "\" must be a torque");
        actuator_ok = false;
      }
      if (!(a.limit > 0)) {
        b.problem("actuator", b.key_path("actuator") + ": \"" + *name + "\" needs a limit (the bang-bang level)");
        actuator_ok = false;
      }
    }
  }
  if (auto k = b.integer_array("modes", 0, 4, false)) {
    for (long long v : *k) {
      if (std::find(st.modes.begin(), st.modes.end(), static_cast<int>(v)) != st.modes.end()) {
        b.problem("modes", b.key_path("modes") + " lists " + std::to_string(v) + " twice; each k at most once");
        continue;
      }
      st.modes.push_back(static_cast<int>(v));
    }
  } else {
    st.modes = {1, 2};
  }
  b.finish();
  for (int k : st.modes)
    for (const char* model : {"first_order", "nonlinear"})
      outputs.fixed("[bang_bang]", "case_bang_bang_k" + std::to_string(k) + "_" + model + ".csv");
  if (!root.has("controller")) b.problem("actuator", "[bang_bang] is compared beside a [controller]; add one");
  d.bang_bang = st;
  if (actuator_ok && problems.empty()) {
    try {
      check_bang_bang_body(b, d);
    } catch (const std::exception&) {
      // the beam or an element is not valid: parse_design's whole-beam check reports it
      // (anything else fails again, and is reported, when the study runs)
    }
  }
}

}  // namespace

std::vector<ForceElement> Design::force_elements() const {
  std::vector<ForceElement> e;
  for (const auto& l : loads) e.push_back(l.element);
  for (const auto& a : actuators) e.push_back(a.element);
  return e;
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
  d.title = root.string("title", false).value_or("");
  Section model = root.table("model");
  d.noa = static_cast<int>(model.integer("noa", 1, kMaxNoa, false).value_or(6));
  model.finish();
  read_beam(root, d);
  Section out = root.table("output");
  d.plots = out.boolean("plots", false).value_or(true);
  out.finish();
  Outputs outputs;
  outputs.fixed("every run", "summary.json");
  read_free_vibration(root, d, outputs);
  const std::vector<std::string> rejected_actuators = read_loads_and_actuators(root, d);
  read_damping(root, d);
  read_simulation(root, d, outputs);
  read_maneuver(root, d, outputs, rejected_actuators);
  read_controller(root, d, outputs, rejected_actuators);
  read_bang_bang(root, d, outputs, problems, rejected_actuators);
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
  // read at most one byte past the limit: the file may have grown since it was measured
  std::string text(lim::kMaxFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw DesignError({where + "cannot read the file"});
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > lim::kMaxFileBytes) throw DesignError({too_large});
  return parse_design(text, path);
}

}  // namespace freeflex
