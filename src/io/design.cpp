#include "freeflex/io/design.hpp"

#include <algorithm>
#include <fstream>
#include <limits>
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

std::optional<ForceElement> read_element(Section& s, double length, bool& ok) {
  ForceElement e;
  auto name = s.string("name", true, true);
  auto type = s.choice("type", {"force", "thruster", "torque"}, true);
  const Range on_beam = length > 0 ? Range::closed(0.0, length) : Range::nonnegative();
  auto pos = s.number("position_m", on_beam, true);
  if (type && *type == "torque") {
    if (s.has("direction")) s.problem("direction", s.key_path("direction") + " does not apply to a torque");
    if (s.has("follow_slope")) s.problem("follow_slope", s.key_path("follow_slope") + " applies to thrusters only");
    s.number_array("direction", Range(), false);
    s.boolean("follow_slope", false);
  } else {
    const auto dir = s.number_array("direction", Range(), true);
    if (dir && dir->size() == 2) {
      e.direction = Eigen::Vector2d((*dir)[0], (*dir)[1]);
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
  auto times = p.number_array("times_s", Range::nonnegative(), true);
  auto values = p.number_array("values", Range(), true);
  p.finish();
  if (!type || !times || !values) return std::nullopt;
  for (std::size_t i = 1; i < times->size(); ++i)
    if (!((*times)[i] > (*times)[i - 1])) {
      std::ostringstream os;
      os << p.key_path("times_s") << " must be strictly increasing: entry " << i + 1 << " (" << (*times)[i]
         << ") does not exceed entry " << i << " (" << (*times)[i - 1] << ")";
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

void read_loads_and_actuators(Section& root, Design& d) {
  const double L = beam_length(d);
  std::vector<std::pair<std::string, Section*>> names;
  auto loads = root.table_array("load");
  auto acts = root.table_array("actuator");
  for (auto& s : loads) {
    bool ok = true;
    auto e = read_element(s, L, ok);
    auto prof = read_profile(s);
    s.finish();
    if (e && ok && prof) d.loads.push_back({*e, *prof});
  }
  for (auto& s : acts) {
    bool ok = true;
    auto e = read_element(s, L, ok);
    const double limit = s.number("limit", Range::positive(), false).value_or(0.0);
    s.finish();
    if (e && ok) d.actuators.push_back({*e, limit});
  }
  std::vector<std::string> seen;
  auto check_name = [&](const ForceElement& e, Section& s) {
    if (std::find(seen.begin(), seen.end(), e.name) != seen.end())
      s.problem("name", s.key_path("name") + " = \"" + e.name + "\" is used twice; load and actuator names must be unique");
    seen.push_back(e.name);
  };
  for (std::size_t i = 0, k = 0; i < loads.size() && k < d.loads.size(); ++i)
    if (loads[i].has("name")) check_name(d.loads[k++].element, loads[i]);
  for (std::size_t i = 0, k = 0; i < acts.size() && k < d.actuators.size(); ++i)
    if (acts[i].has("name")) check_name(d.actuators[k++].element, acts[i]);
}

void read_damping(Section& root, Design& d) {
  Section s = root.table("damping");
  if (!s.present()) return;
  if (auto r = s.number_array("ratios", Range{0.0, 1.0, false, true}, true)) d.damping_ratios = *r;
  s.finish();
}

void read_simulation(Section& root, Design& d) {
  Section s = root.table("simulation");
  if (!s.present()) return;
  SimulationStudy st;
  SimulationOptions& o = st.options;
  auto dur = s.number("duration_s", Range::positive(), true);
  if (dur) o.duration_s = *dur;
  o.output_step_s = s.number("output_step_s", Range::positive(), false).value_or(o.duration_s / 600.0);
  if (dur && o.output_step_s > o.duration_s)
    s.problem("output_step_s", s.key_path("output_step_s") + " must not exceed duration_s");
  o.trajectory_step_s = s.number("trajectory_step_s", Range::positive(), false).value_or(1e-3);
  o.integrator.rtol = s.number("rtol", Range{0.0, 1.0, true, true}, false).value_or(1e-8);
  o.integrator.atol = s.number("atol", Range::positive(), false).value_or(1e-10);
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
  if (!st.nonlinear && !st.perturbation)
    s.problem("nonlinear", s.key_path("nonlinear") + " and perturbation are both false: nothing to simulate");
  st.rigid_figure = s.string("rigid_figure", false, true).value_or(st.rigid_figure);
  st.elastic_figure = s.string("elastic_figure", false, true).value_or(st.elastic_figure);
  s.finish();
  if (d.loads.empty() && !root.has("maneuver"))
    s.problem("duration_s", "[simulation] needs at least one [[load]] or a [maneuver] to respond to");
  d.simulation = st;
}

/// Resolves [[actuator]] names to element indices (loads come first in force_elements()).
std::vector<int> actuator_indices(Section& s, const std::string& key, const std::vector<std::string>& names,
                                  const Design& d) {
  std::vector<int> idx;
  for (const auto& name : names) {
    int found = -1;
    for (std::size_t i = 0; i < d.actuators.size(); ++i)
      if (d.actuators[i].element.name == name) found = static_cast<int>(i);
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
  auto pair = [&](const std::string& k, int at) {
    auto v = s.number_array(k, Range(), false);
    if (!v) return;
    if (v->size() != 2) {
      s.problem(k, s.key_path(k) + " must have two components [x, y], got " + std::to_string(v->size()));
      return;
    }
    x(at) = (*v)[0];
    x(at + 1) = (*v)[1];
  };
  pair("position_m", 0);
  pair("velocity_m_s", 3);
  x(2) = s.number("theta_deg", Range(), false).value_or(0.0) * M_PI / 180.0;  // degrees only in files
  x(5) = s.number("theta_rate_deg_s", Range(), false).value_or(0.0) * M_PI / 180.0;
  s.finish();
  return x;
}

void read_maneuver(Section& root, Design& d) {
  Section m = root.table("maneuver");
  if (!m.present()) return;
  ManeuverStudy st;
  ManeuverProblem& p = st.problem;
  TrajoptOptions& o = st.options;
  // actuators by name, with their limits as bounds
  if (auto list = m.string_array("actuators", true)) {
    p.actuators = actuator_indices(m, "actuators", *list, d);
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
  auto dur = m.number("duration_s", Range::positive(), !p.free_time);
  p.t_min_s = m.number("duration_min_s", Range::positive(), false).value_or(0.1);
  p.t_max_s = m.number("duration_max_s", Range::positive(), false).value_or(10.0);
  p.duration_s = dur.value_or(0.5 * (p.t_min_s + p.t_max_s));
  if (p.free_time && p.t_min_s > p.t_max_s)
    m.problem("duration_min_s", m.key_path("duration_min_s") + " must not exceed duration_max_s");
  p.w_energy = objective == "energy" ? 1.0 : 0.0;
  p.w_time = objective == "time" ? 1.0 : 0.0;
  p.w_smooth = objective == "smooth" ? 1.0 : 0.0;
  if (objective == "weighted") {
    p.w_energy = m.number("energy_weight", Range::nonnegative(), false).value_or(0.0);
    p.w_time = m.number("time_weight", Range::nonnegative(), false).value_or(0.0);
    p.w_smooth = m.number("smooth_weight", Range::nonnegative(), false).value_or(0.0);
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
  if (auto w = m.number_array("actuator_weights", Range::nonnegative(), false)) {
    if (w->size() != nu) m.problem("actuator_weights", m.key_path("actuator_weights") + " needs one entry per actuator (" + std::to_string(nu) + ")");
    else p.energy_weights = Eigen::Map<const Eigen::VectorXd>(w->data(), static_cast<Eigen::Index>(w->size()));
  }
  if (auto r = m.number_array("rate_limits", Range::positive(), false)) {
    if (r->size() != nu) m.problem("rate_limits", m.key_path("rate_limits") + " needs one entry per actuator (" + std::to_string(nu) + ")");
    else p.du_max = Eigen::Map<const Eigen::VectorXd>(r->data(), static_cast<Eigen::Index>(r->size()));
  }
  const std::string tr =
      m.choice("transcription", {"hermite_simpson", "hermite_simpson_compressed", "trapezoidal"}, false)
          .value_or("hermite_simpson");
  o.transcription = tr == "trapezoidal"                  ? Transcription::Trapezoidal
                    : tr == "hermite_simpson_compressed" ? Transcription::HermiteSimpsonCompressed
                                                         : Transcription::HermiteSimpson;
  o.intervals = static_cast<int>(m.integer("intervals", 1, 100000, false).value_or(100));
  o.mesh_refinements = static_cast<int>(m.integer("mesh_refinements", 0, 20, false).value_or(0));
  o.mesh_tolerance = m.number("mesh_tolerance", Range::positive(), false).value_or(1e-6);
  o.tol = m.number("tolerance", Range{0.0, 1.0, true, true}, false).value_or(1e-8);
  o.max_iter = static_cast<int>(m.integer("max_iterations", 1, 1000000, false).value_or(3000));
  o.verbose = !m.boolean("quiet", false).value_or(false);
  Section ip = m.table("ipopt");
  if (ip.present()) {
    for (const auto& [key, value] : ip.raw_entries()) o.ipopt_options.emplace_back(key, value);
  }
  m.finish();
  d.maneuver = st;
}

void read_controller(Section& root, Design& d) {
  Section c = root.table("controller");
  if (!c.present()) return;
  ControllerStudy st;
  c.choice("type", {"tvlqr"}, false);
  if (auto names = c.string_array("actuators", true)) {
    st.actuators = actuator_indices(c, "actuators", *names, d);
    if (st.actuators.size() == names->size()) st.actuator_names = *names;
  }
  const std::size_t m = st.actuators.size();
  st.limits.resize(static_cast<Eigen::Index>(m));
  for (std::size_t k = 0; k < m; ++k) {
    const double lim = d.actuators[st.actuators[k] - d.loads.size()].limit;
    st.limits(static_cast<Eigen::Index>(k)) = lim > 0 ? lim : std::numeric_limits<double>::infinity();
  }
  st.horizon_s = c.number("horizon_s", Range::positive(), true).value_or(st.horizon_s);
  auto state_weight = [&](const char* key) {
    const double w = c.number(key, Range(), false).value_or(1.0);
    if (w < 0.0) {
      c.problem(key, c.key_path(key) + " = " + std::to_string(w) +
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
    auto w = c.number_array("input_weights", Range(), false);
    bool pd = true;
    if (w)
      for (double x : *w) pd = pd && x > 0.0;
    if (!w) {
      // reported by number_array
    } else if (!pd) {
      c.problem("input_weights", c.key_path("input_weights") +
                                     ": every entry must be > 0 (the input weight R must be positive definite)");
    } else if (w->size() != m) {
      c.problem("input_weights", c.key_path("input_weights") + " needs one entry per actuator (" + std::to_string(m) + ")");
    } else {
      st.input_weights = Eigen::Map<const Eigen::VectorXd>(w->data(), static_cast<Eigen::Index>(m));
    }
  }
  if (st.weight_elastic + st.weight_rigid_position + st.weight_rigid_rate <= 0.0)
    c.problem("weight_elastic", "controller: every state weight is zero; Q must weight something");
  st.grid_step_s = c.number("grid_step_s", Range::positive(), false).value_or(0.005);
  st.simulate_until_s = c.number("simulate_until_s", Range::positive(), false).value_or(st.horizon_s);
  st.figure = c.string("figure", false, true).value_or("comparison");
  c.finish();
  if (!d.loads.empty() && !d.maneuver) {
    double end = 0.0;
    for (const auto& l : d.loads) end = std::max(end, l.profile.times().back());
    if (st.horizon_s < end)
      c.problem("horizon_s", c.key_path("horizon_s") + " = " + std::to_string(st.horizon_s) +
                                 ", shorter than the maneuver (its loads act until " + std::to_string(end) + " s)");
  }
  if (d.maneuver) {
    for (int a : d.maneuver->problem.actuators)
      if (std::find(st.actuators.begin(), st.actuators.end(), a) == st.actuators.end())
        c.problem("actuators", c.key_path("actuators") + " must include every maneuver actuator (the feedback adds "
                                                         "to their commands)");
  }
  d.controller = st;
}

void read_bang_bang(Section& root, Design& d) {
  Section b = root.table("bang_bang");
  if (!b.present()) return;
  BangBangStudy st;
  if (auto name = b.string("actuator", true)) {
    const auto idx = actuator_indices(b, "actuator", {*name}, d);
    if (!idx.empty()) {
      st.actuator = idx[0];
      st.actuator_name = *name;
      const ActuatorSpec& a = d.actuators[static_cast<std::size_t>(idx[0]) - d.loads.size()];
      if (a.element.type != ForceElement::Type::Torque) b.problem("actuator", b.key_path("actuator") + ": \"" + *name + "\" must be a torque");
      if (!(a.limit > 0)) b.problem("actuator", b.key_path("actuator") + ": \"" + *name + "\" needs a limit (the bang-bang level)");
    }
  }
  if (auto k = b.integer_array("modes", 0, 4, false)) st.modes.assign(k->begin(), k->end());
  else st.modes = {1, 2};
  b.finish();
  if (!root.has("controller")) b.problem("actuator", "[bang_bang] is compared beside a [controller]; add one");
  d.bang_bang = st;
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
  read_loads_and_actuators(root, d);
  read_damping(root, d);
  read_simulation(root, d);
  read_maneuver(root, d);
  read_controller(root, d);
  read_bang_bang(root, d);
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
