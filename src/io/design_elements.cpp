// [[load]], [[actuator]] and [damping]: the force elements, their time profiles and
// limits, and the modal damping ratios.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "io/design_sections.hpp"

namespace freeflex::io_detail {

namespace {

std::optional<ForceElement> read_element(Section& s, double length, bool& ok, std::string& name_read) {
  ForceElement e;
  auto name = s.string("name", true, true);
  if (name) name_read = *name;
  const auto type = s.enumerated<ForceElement::Type>("type", true);
  const Range on_beam = length > 0 ? Range::closed(0.0, length) : Range::nonnegative();
  auto pos = s.number("position_m", on_beam, true);
  if (type == ForceElement::Type::Torque) {
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
    if (type == ForceElement::Type::Force && s.has("follow_slope"))
      s.problem("follow_slope", s.key_path("follow_slope") + " applies to thrusters only");
    e.follow_slope = s.boolean("follow_slope", false).value_or(false);
  }
  if (!name || !type || !pos) {
    ok = false;
    return std::nullopt;
  }
  e.name = *name;
  e.type = *type;
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
  const auto type = p.enumerated<TimeProfile::Kind>("type", true);
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
  const bool steps = *type == TimeProfile::Kind::Steps;
  const std::size_t expect = steps ? times->size() - 1 : times->size();
  if (values->size() != expect) {
    p.problem("values", p.key_path("values") + " has " + std::to_string(values->size()) + " entries, must have " +
                            std::to_string(expect) + (steps ? " (one per interval between times_s)" : " (one per time)"));
    return std::nullopt;
  }
  return TimeProfile(*type, *times, *values);
}

}  // namespace

std::vector<std::string> read_loads_and_actuators(Section& root, Design& d) {
  const double L = beam_length(d);
  std::vector<std::string> seen, rejected;
  auto check_name = [&](const std::string& name, Section& s) {
    if (name.empty()) return;  // missing or not a string: reported by read_element
    if (std::find(seen.begin(), seen.end(), name) != seen.end())
      s.problem("name", s.key_path("name") + " = \"" + name + "\" is used twice; load and actuator names must be unique");
    seen.push_back(name);
  };
  std::vector<Section> loads = root.table_array("load"), actuators = root.table_array("actuator");
  // each element adds work to every step of every simulation: bounded before any
  if (loads.size() + actuators.size() > static_cast<std::size_t>(lim::kMaxForceElements)) {
    root.problem(loads.empty() ? "actuator" : "load",
                 std::to_string(loads.size()) + " [[load]] and " + std::to_string(actuators.size()) +
                     " [[actuator]] tables; at most " + std::to_string(lim::kMaxForceElements) + " together");
    return rejected;
  }
  std::size_t profile_times = 0;
  for (auto& s : loads) {
    bool ok = true;
    std::string name;
    auto e = read_element(s, L, ok, name);
    auto prof = read_profile(s);
    s.finish();
    check_name(name, s);
    if (e && ok && prof) d.loads.push_back({*e, *prof});
    if (prof && (profile_times += prof->times().size()) > lim::kMaxProfileTimes)
      s.problem("profile", s.key_path("profile") + ": the load profiles have " + std::to_string(profile_times) +
                               " times_s entries up to here; at most " +
                               std::to_string(lim::kMaxProfileTimes) + " together (each is a breakpoint of every simulation)");
  }
  for (auto& s : actuators) {
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


}  // namespace freeflex::io_detail
