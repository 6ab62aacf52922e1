// [[sensor]], [lqg] and [sweep]: the sensors and the Kalman filter of output feedback, the
// plant's departures (gain, lag, delay, noise), and the uncertain parameters of a sweep
// with their distributions. Every problem is reported before any sample runs.
#include <cmath>

#include "io/design_sections.hpp"

namespace freeflex::io_detail {
namespace {

const Range kRate = Range::positive().supported(1e-3, 1e6);  // sample rates [Hz]

/// Sample times at `rate` over [0, span], as sample_times() makes them.
double samples_over(double span, double rate) { return std::ceil(span * rate - 1e-9) + 1.0; }

/// The flights of [lqg] and [sweep] keep every sample's command (a sweep's sample, every
/// state): at most kMaxOutputRows samples over simulate_until_s. False when refused.
bool check_flight(Section& s, const Design& d, const std::string& key, const std::string& lead, double rate) {
  if (!d.controller) return true;
  return check_count(s, key, lead, "controller.simulate_until_s = " + shortest(d.controller->simulate_until_s),
                     d.controller->simulate_until_s, 1.0 / rate, "samples of each flight", lim::kMaxOutputRows,
                     "lower the sample rate or shorten simulate_until_s");
}

/// Doubles kept per sample by the digital TV-LQR over the horizon: its gains (m n) and,
/// when it cannot reuse the filter's model (over simulate_until_s), its own
/// discretization (Φ, Γ, Q_d, d: 2 n² + n (m + 1)).
double law_doubles_per_sample(const Design& d, bool own_model) {
  const double n = 2.0 * (3 + d.noa), m = static_cast<double>(d.controller->actuators.size());
  return n * m + (own_model ? 2.0 * n * n + n * (m + 1.0) : 0.0);
}

/// The matrices a digital law (and with `filter`, the Kalman filter: its model and P⁻, P⁺,
/// L at every sample, 4 n² + n (m + p + 1)) keep, bounded like the TV-LQR's gains
/// (kMaxGainStorage doubles). False when refused.
bool check_storage(Section& s, const Design& d, const std::string& key, const std::string& lead, double rate,
                   bool filter) {
  if (!d.controller) return true;
  const ControllerStudy& c = *d.controller;
  const double n = 2.0 * (3 + d.noa), m = static_cast<double>(c.actuators.size());
  const double p = static_cast<double>(d.sensors.size());
  const double k_until = samples_over(c.simulate_until_s, rate), k_horizon = samples_over(c.horizon_s, rate);
  // the law reuses the filter's model only when both cover the same span
  const bool own_model = !filter || c.simulate_until_s != c.horizon_s;
  const double doubles = (filter ? k_until * (4.0 * n * n + n * (m + p + 1.0)) : 0.0) +
                         k_horizon * law_doubles_per_sample(d, own_model);
  if (doubles <= lim::kMaxGainStorage) return true;
  s.problem(key, lead + (filter ? " keeps the Kalman filter over controller.simulate_until_s = " +
                                      shortest(c.simulate_until_s) + " s and" : " keeps") +
                     " the digital TV-LQR over horizon_s = " + shortest(c.horizon_s) + " s at noa = " +
                     std::to_string(d.noa) + " (" + shortest(n) + " states): " + show_count(std::ceil(doubles)) +
                     " doubles; at most " + shortest(lim::kMaxGainStorage) +
                     " (400 MB): lower the sample rate, shorten the spans or lower noa");
  return false;
}

void read_sensors(Section& root, Design& d) {
  const double length = beam_length(d);
  std::vector<Section> sensors = root.table_array("sensor");
  // each is a row of C: the filter's gain and innovation are p x p and n x p at every sample
  if (sensors.size() > static_cast<std::size_t>(lim::kMaxSensors)) {
    root.problem("sensor", std::to_string(sensors.size()) + " [[sensor]] tables; at most " +
                               std::to_string(lim::kMaxSensors));
    return;
  }
  for (Section& s : sensors) {
    Sensor sensor;
    auto name = s.string("name", true, true);
    auto type = s.enumerated<Sensor::Type>("type", true);
    const bool at_point = type && (*type == Sensor::Type::Strain || *type == Sensor::Type::TipDisplacement);
    const Range on_beam = length > 0 ? Range::closed(0.0, length) : Range::nonnegative();
    auto pos = s.number("position_m", on_beam, at_point);
    if (type && !at_point && s.has("position_m"))
      s.problem("position_m", s.key_path("position_m") + " does not apply to a " + to_string(*type) +
                                  " (gyros sit at o and see the rigid attitude)");
    auto density = s.number("noise_density", Range::positive().supported(1e-15, 1e6), true);
    s.finish();
    if (!name || !type || !density) continue;
    sensor.name = *name;
    sensor.type = *type;
    sensor.position_m = pos.value_or(0.0);
    sensor.noise_density = *density;
    for (const Sensor& other : d.sensors)
      if (other.name == sensor.name) s.problem("name", s.key_path("name") + " = \"" + sensor.name + "\" is used by another sensor");
    d.sensors.push_back(sensor);
  }
}

void read_plant(Section& s, PlantOptions& p) {
  p.actuator_gain = s.number("actuator_gain", Range::positive().supported(1e-6, 1e6), false).value_or(p.actuator_gain);
  p.lag_s = s.number("lag_s", Range::nonnegative().supported(0.0, lim::kMaxTime_s), false).value_or(p.lag_s);
  p.delay_s = s.number("delay_s", Range::nonnegative().supported(0.0, lim::kMaxTime_s), false).value_or(p.delay_s);
  p.seed = static_cast<std::uint64_t>(s.integer("seed", 0, (1LL << 62), false).value_or(static_cast<long long>(p.seed)));
}

void read_lqg(Section& root, Design& d, Outputs& outputs) {
  Section s = root.table("lqg");
  if (!s.present()) return;
  LqgStudy st;
  st.sample_rate_hz = s.number("sample_rate_hz", kRate, false).value_or(st.sample_rate_hz);
  const std::size_t m = d.controller ? d.controller->actuators.size() : 0;
  st.process_noise_density = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(m), 0.01);
  if (auto w = s.number_array("process_noise_density", Range::nonnegative().supported(0.0, 1e6), false)) {
    if (d.controller && w->size() != m)
      s.problem("process_noise_density", s.key_path("process_noise_density") + " needs one entry per controller actuator (" +
                                             std::to_string(m) + "), got " + std::to_string(w->size()));
    else if (d.controller)
      st.process_noise_density = Eigen::Map<const Eigen::VectorXd>(w->data(), static_cast<Eigen::Index>(m));
  }
  st.initial_std = s.number("initial_std", Range::positive().supported(1e-12, 1e6), false).value_or(st.initial_std);
  read_plant(s, st.plant);
  st.plant.process_noise_density = st.process_noise_density;
  st.delay_known = s.boolean("delay_known", false).value_or(false);
  st.error_estimate = s.boolean("error_estimate", false).value_or(st.error_estimate);
  if (st.delay_known) {
    const double r = st.plant.delay_s * st.sample_rate_hz;
    if (std::abs(r - std::round(r)) > 1e-6)
      s.problem("delay_known", s.key_path("delay_known") + " = true needs delay_s = " + shortest(st.plant.delay_s) +
                                   " to be a whole number of samples at sample_rate_hz = " + shortest(st.sample_rate_hz));
  }
  if (auto t = s.string("table", false, true)) st.table = *t;
  if (auto f = s.string("figure", false, true)) st.figure = *f;
  s.finish();
  outputs.named(s, "table", st.table, {".csv"});
  outputs.named(s, "figure", st.figure, {".gp", ".png"});
  outputs.fixed("[lqg]", st.table + "_history.csv");
  if (!root.has("controller")) s.problem("sample_rate_hz", "[lqg] flies the [controller]'s TV-LQR: add a [controller]");
  if (d.sensors.empty()) s.problem("sample_rate_hz", "[lqg] needs at least one [[sensor]]");
  const std::string lead = s.key_path("sample_rate_hz") + " = " + shortest(st.sample_rate_hz) +
                           (s.has("sample_rate_hz") ? "" : " (the default)");
  if (check_flight(s, d, "sample_rate_hz", lead, st.sample_rate_hz))
    check_storage(s, d, "sample_rate_hz", lead, st.sample_rate_hz, true);
  d.lqg = st;
}

/// The bounds a parameter's values must respect, and its unit for messages.
struct Bounds {
  double lo, hi;
  bool lo_open;
  const char* what;
};
Bounds bounds_of(SweepParameter::Name n) {
  using N = SweepParameter::Name;
  switch (n) {
    case N::BendingStiffnessScale: return {0.0, 100.0, true, "a factor on every segment's EI"};
    case N::MassScale: return {0.0, 100.0, true, "a factor on every segment's mass per length"};
    case N::DampingRatio: return {0.0, 1.0, false, "the modal damping ratio of every elastic mode"};
    case N::ActuatorGain: return {0.0, 100.0, true, "a factor on every command"};
    case N::DelayS: return {0.0, 10.0, false, "seconds"};
    case N::LagS: return {0.0, 10.0, false, "seconds"};
  }
  return {0.0, 1.0, false, ""};
}

void read_sweep(Section& root, Design& d, Outputs& outputs) {
  Section s = root.table("sweep");
  if (!s.present()) return;
  SweepStudy st;
  st.samples = static_cast<int>(s.integer("samples", 1, 1000000, true).value_or(st.samples));
  st.seed = static_cast<std::uint64_t>(s.integer("seed", 0, (1LL << 62), false).value_or(1));
  if (auto fb = s.enumerated<SampledLoopOptions::Feedback>("feedback", false)) st.feedback = *fb;
  st.sample_rate_hz = s.number("sample_rate_hz", kRate, false).value_or(st.sample_rate_hz);
  auto req = s.number("requirement_energy_J", Range::positive().supported(1e-300, 1e12), true);
  st.requirement_energy_J = req.value_or(0.0);
  st.error_estimate = s.boolean("error_estimate", false).value_or(st.error_estimate);
  if (auto t = s.string("table", false, true)) st.table = *t;
  if (auto f = s.string("figure", false, true)) st.figure = *f;
  for (const auto& [name, key_text] : EnumNames<SweepParameter::Name>::names) {
    const std::string key = key_text;
    Section p = s.table(key);
    if (!p.present()) continue;
    SweepParameter sp;
    sp.name = name;
    const Bounds b = bounds_of(name);
    const auto kind = p.enumerated<SweepParameter::Kind>("distribution", true);
    const Range any = Range().supported(-1e12, 1e12);
    auto check_value = [&](const std::string& k, double v) {
      const bool below = b.lo_open ? !(v > b.lo) : !(v >= b.lo);
      if (below || v > b.hi)
        p.problem(k, p.key_path(k) + " = " + shortest(v) + ", must be in " + (b.lo_open ? "(" : "[") + shortest(b.lo) +
                         ", " + shortest(b.hi) + "] (" + key + " is " + b.what + ")");
      return !(below || v > b.hi);
    };
    if (kind == SweepParameter::Kind::Normal) {
      auto mean = p.number("mean", any, true);
      auto sd = p.number("std", Range().supported(-1e12, 1e12), true);
      if (sd && !(*sd > 0.0))
        p.problem("std", p.key_path("std") + " = " + shortest(*sd) + ", must be > 0 (a standard deviation)");
      if (mean && check_value("mean", *mean) && sd && *sd > 0.0) {
        sp.a = *mean;
        sp.b = *sd;
        if (!(*mean - 5.0 * *sd >= b.lo))  // draws are clamped to the bounds, which then must be 5σ away
          p.problem("std", p.key_path("std") + " = " + shortest(*sd) + ": mean - 5 std = " + shortest(*mean - 5.0 * *sd) +
                               " falls below " + shortest(b.lo) + "; " + key + " must stay " +
                               (b.lo_open ? "> " : ">= ") + shortest(b.lo));
      }
      for (const char* k : {"min", "max", "points"})
        if (p.has(k)) p.problem(k, p.key_path(k) + " does not apply to distribution = \"normal\" (mean, std)");
    } else if (kind) {
      auto lo = p.number("min", any, true);
      auto hi = p.number("max", any, true);
      const bool ok_lo = lo && check_value("min", *lo), ok_hi = hi && check_value("max", *hi);
      if (kind == SweepParameter::Kind::Grid) sp.points = static_cast<int>(p.integer("points", 2, 1000, true).value_or(2));
      if (ok_lo && ok_hi) {
        if (!(*lo < *hi))
          p.problem("max", p.key_path("min") + " = " + shortest(*lo) + ", max = " + shortest(*hi) +
                               ": an empty range; expected min < max");
        sp.a = *lo;
        sp.b = *hi;
      }
      for (const char* k : {"mean", "std"})
        if (p.has(k)) p.problem(k, p.key_path(k) + " does not apply to distribution = \"" + to_string(*kind) + "\" (min, max)");
      if (*kind == SweepParameter::Kind::Uniform && p.has("points"))
        p.problem("points", p.key_path("points") + " applies to distribution = \"grid\" only");
    }
    if (kind) sp.kind = *kind;
    p.finish();
    st.parameters.push_back(sp);
  }
  s.finish();
  if (st.parameters.empty())
    s.problem("samples", "[sweep] varies nothing: add at least one parameter table, one of [sweep.bending_stiffness_scale], "
                         "[sweep.mass_scale], [sweep.damping_ratio], [sweep.actuator_gain], [sweep.delay_s], [sweep.lag_s]");
  if (st.total_samples() > 1000000)
    s.problem("samples", "[sweep] asks for " + std::to_string(st.total_samples()) +
                             " samples (samples times the grid points); at most 1000000");
  outputs.named(s, "table", st.table, {".csv"});
  outputs.named(s, "figure", st.figure, {".gp", ".png"});
  outputs.fixed("[sweep]", st.figure + "_counts.csv");
  if (!root.has("controller")) s.problem("samples", "[sweep] flies the [controller]'s TV-LQR: add a [controller]");
  if (st.feedback == SampledLoopOptions::Feedback::Lqg && !root.has("lqg"))
    s.problem("feedback", s.key_path("feedback") + " = \"lqg\" needs an [lqg] section (the filter's settings)");
  // the samples fly at the [lqg]'s rate with its filter (bounded there) or at this rate
  const bool lqg = st.feedback == SampledLoopOptions::Feedback::Lqg;
  if (d.controller && (!lqg || d.lqg)) {
    const double rate = lqg ? d.lqg->sample_rate_hz : st.sample_rate_hz;
    const std::string key = lqg || !s.has("sample_rate_hz") ? "samples" : "sample_rate_hz";
    const std::string lead = lqg ? s.key_path("feedback") + " = \"lqg\" at lqg.sample_rate_hz = " + shortest(rate)
                                 : s.key_path("sample_rate_hz") + " = " + shortest(rate) +
                                       (s.has("sample_rate_hz") ? "" : " (the default)");
    // with "lqg" the flights and the filter are bounded at [lqg] sample_rate_hz (reported there)
    const bool bounded = lqg ? samples_over(d.controller->simulate_until_s, rate) <= lim::kMaxOutputRows
                             : check_flight(s, d, key, lead, rate) && check_storage(s, d, key, lead, rate, false);
    if (bounded) {
      // the least work of the samples: one step per sample interval and the plant built
      const double intervals = samples_over(d.controller->simulate_until_s, rate) - 1.0;
      const double per_sample = intervals * static_cast<double>(step_work(2 * (3 + d.noa), IntegratorOptions::Method::Adams)) +
                                static_cast<double>(body_build_work(d));
      const double least = per_sample * static_cast<double>(st.total_samples());
      if (least > static_cast<double>(lim::kMaxSweepWork))
        s.problem("samples", s.key_path("samples") + " = " + std::to_string(st.samples) + " gives " +
                                 std::to_string(st.total_samples()) + " samples of " + show_count(intervals) +
                                 " sample intervals each (" + lead + "), at least " + show_count(std::ceil(least)) +
                                 " work units (one step per interval and the plant built, " +
                                 show_count(std::ceil(per_sample)) + " a sample); at most " +
                                 shortest(static_cast<double>(lim::kMaxSweepWork)) +
                                 " for a sweep (README, the \"(limits)\" row): fewer samples, a lower rate or a "
                                 "shorter simulate_until_s");
    }
  }
  d.sweep = st;
}

}  // namespace

void read_sensors_lqg_sweep(Section& root, Design& d, Outputs& outputs) {
  read_sensors(root, d);
  read_lqg(root, d, outputs);
  read_sweep(root, d, outputs);
}

}  // namespace freeflex::io_detail

namespace freeflex {

long SweepStudy::total_samples() const {
  long n = samples;
  for (const SweepParameter& p : parameters)
    if (p.kind == SweepParameter::Kind::Grid) n *= p.points;
  return n;
}

}  // namespace freeflex
