// [motion]: the reference frame's motion prescribed (docs/theory.md section 14, eq. 14.10).
#include <cmath>
#include <stdexcept>

#include "io/design_sections.hpp"

namespace freeflex::io_detail {
namespace {

/// [motion.theta], [motion.x] or [motion.y]: a spin-up ramp or a table. `unit` is "deg"
/// (θ, read in degrees, kept in radians) or "m".
std::optional<MotionProfile> read_profile(Section& m, const std::string& key, const std::string& unit,
                                          std::size_t& times) {
  Section s = m.table(key);
  if (!s.present()) return MotionProfile();
  const bool deg = unit == "deg";
  const double scale = deg ? M_PI / 180.0 : 1.0;
  const double max_value = deg ? lim::kMaxAngle_deg : lim::kMaxPosition_m;
  const double max_rate = deg ? lim::kMaxRate_deg_s : lim::kMaxVelocity_m_s;
  const std::string rate_unit = deg ? "deg_s" : "m_s";
  std::optional<MotionProfile> out;
  const auto type = s.choice("type", {"spin_up", "table"}, true);
  if (type == "spin_up") {
    const auto rate = s.number("final_rate_" + rate_unit, Range().supported(-max_rate, max_rate), true);
    const auto ramp = s.number("ramp_time_s", kTime, true);
    if (rate && ramp) out = MotionProfile::spin_up(*rate * scale, *ramp);
  } else if (type == "table") {
    const auto t = s.number_array("times_s", Range::nonnegative().supported(-kInf, lim::kMaxTime_s), true);
    const auto v = s.number_array("values_" + unit, Range().supported(-max_value, max_value), true);
    const auto r = s.number_array("rates_" + rate_unit, Range().supported(-max_rate, max_rate), true);
    const auto a = s.number_array("accelerations_" + rate_unit + "2", Range().supported(-1e12, 1e12), true);
    const bool too_many = t && (times += t->size()) > lim::kMaxProfileTimes;
    if (too_many)
      s.problem("times_s", s.key_path("times_s") + ": the load profiles and motion tables have " +
                               std::to_string(times) + " times_s entries up to here; at most " +
                               std::to_string(lim::kMaxProfileTimes) + " together");
    if (t && v && r && a && !too_many) {
      auto scaled = [scale](std::vector<double> x) {
        for (double& e : x) e *= scale;
        return x;
      };
      try {
        out = MotionProfile::table(*t, scaled(*v), scaled(*r), scaled(*a));
      } catch (const std::invalid_argument& e) {
        s.problem("times_s", s.key_path("times_s") + ": " + std::string(e.what()).substr(std::string("MotionProfile::table: ").size()) +
                                 " (times_s, values_" + unit + ", rates_" + rate_unit + " and accelerations_" +
                                 rate_unit + "2 are the columns of one table)");
      }
    }
  }
  s.finish();
  return out;
}

}  // namespace

void read_motion(Section& root, Design& d) {
  Section m = root.table("motion");
  if (!m.present()) return;
  MotionSpec spec;
  spec.hub_radius_m =
      m.number("hub_radius_m", Range::nonnegative().supported(-kInf, lim::kMaxLength_m), false).value_or(0.0);
  std::size_t times = 0;  // bounded with the load profiles' (design_limits::kMaxProfileTimes)
  for (const auto& l : d.loads) times += l.profile.times().size();
  const auto th = read_profile(m, "theta", "deg", times);
  const auto x = read_profile(m, "x", "m", times);
  const auto y = read_profile(m, "y", "m", times);
  if (!m.has("theta") && !m.has("x") && !m.has("y"))
    m.problem("theta", "[motion] prescribes nothing: add [motion.theta], [motion.x] or [motion.y]");
  for (const char* other : {"maneuver", "controller", "bang_bang"})
    if (root.has(other))
      m.problem("theta", std::string("[motion] prescribes the reference motion; [") + other +
                             "] needs a free body: use one or the other");
  m.finish();
  if (th && x && y) {
    spec.theta = *th;
    spec.x = *x;
    spec.y = *y;
    d.motion = spec;
  }
}

}  // namespace freeflex::io_detail
