// [bang_bang]: the torque that flies bang-bang rotations beside the controller, the mode
// counts to leave at rest, and what only the discretized body can tell about them.
#include <algorithm>
#include <cmath>

#include "freeflex/control/switch_time.hpp"
#include "freeflex/dynamics/flexible_body.hpp"
#include "io/design_sections.hpp"

namespace freeflex::io_detail {

namespace {

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
  const FlexibleBody body = d.body();
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
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(body.n());
  bool turns = false, known = true;  // known: every moment is independent of the attitude
  double rotation = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < d.loads.size(); ++i) {
    const LoadSpec& l = d.loads[i];
    bool zero = true;
    for (double v : l.profile.values()) zero = zero && v == 0.0;
    if (zero) continue;
    const Eigen::VectorXd g = body.element_force(static_cast<int>(i), 0.0, q0);  // g(2): moment about o per unit command at rest
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

}  // namespace

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
    st.modes.clear();
    for (long long v : *k) {
      if (std::find(st.modes.begin(), st.modes.end(), static_cast<int>(v)) != st.modes.end()) {
        b.problem("modes", b.key_path("modes") + " lists " + std::to_string(v) + " twice; each k at most once");
        continue;
      }
      st.modes.push_back(static_cast<int>(v));
    }
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

}  // namespace freeflex::io_detail
