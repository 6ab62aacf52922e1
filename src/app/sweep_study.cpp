// [lqg] and [sweep] (app/sweep.hpp): the [controller]'s law flown sampled on the full
// model, on the nominal plant (exact state and LQG) and on every sample of an uncertainty
// sweep, in parallel over threads and MPI ranks, resumable from a journal.
#include "freeflex/app/sweep.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <tuple>

#include "app/study_files.hpp"
#include "app/sweep_files.hpp"
#include "freeflex/io/output.hpp"
#include "freeflex/version.hpp"
#include "freeflex/control/lqr.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

/// Marks a study failed for `why`, keeping it among its warnings and reporting it.
template <class R>
void fail_study(R& r, const StudyLog& log, const std::string& why) {
  r.status = StudyStatus::Failed;
  r.message = r.message.empty() ? why : r.message + "; " + why;
  r.warnings.push_back(why);
  if (log.warn) log.warn(why);
}

}  // namespace

namespace detail {

double main_chain_energy(const SuppressionStudyResult& suppression, const std::string& name) {
  // the main chain's cases are named NAME, or vibration_aware_NAME beside a rigid optimum's
  for (const auto& c : suppression.cases)
    if (c.model == "nonlinear" && (c.name == name || c.name == "vibration_aware_" + name))
      return c.metrics.residual_vibration_energy_J;
  return 0.0;
}

Flight::Flight(const Design& design, const SuppressionStudyResult& suppression, const ManeuverStudyResult* maneuver)
    : body(design.body()),  // the suppression study's: its basis, stiffening and damping
      loads(design.excitation()),
      nominal(suppression.chain.nominal) {
  const ControllerStudy& st = *design.controller;
  if (maneuver && maneuver->flown) u0 = maneuver_actuator_commands(*maneuver->flown, st.actuators);  // as suppress_vibration
  model = std::make_unique<FirstOrderModel>(body, *nominal, nominal_element_commands(loads, st.actuators, u0),
                                            st.actuators);
}

KalmanResult design_filter(const Design& design, const Flight& f, std::shared_ptr<WorkBudget> budget) {
  const LqgStudy& lq = *design.lqg;
  const Eigen::MatrixXd C = output_matrix(f.body, design.sensors);
  const Eigen::MatrixXd V = measurement_variance(design.sensors, lq.sample_rate_hz).asDiagonal();
  const Eigen::MatrixXd W = lq.process_noise_density.cwiseAbs2().asDiagonal();
  const int n = f.model->state_size();
  const Eigen::MatrixXd P0 = Eigen::MatrixXd::Identity(n, n) * (lq.initial_std * lq.initial_std);
  DiscretizeOptions o;
  o.integrator.budget = std::move(budget);
  return design_kalman(ltv_system(*f.model), C, V, W, P0, 0.0, design.controller->simulate_until_s, lq.sample_rate_hz,
                       o);
}

TvlqrResult design_digital_law(const Design& design, const Flight& f, const TvlqrResult& continuous, double rate,
                               std::shared_ptr<WorkBudget> budget, const DiscreteLtv* model) {
  const ControllerStudy& st = *design.controller;
  const std::vector<double> times = sample_times(0.0, st.horizon_s, rate);
  DiscreteLtv own;
  if (!model || model->t != times) {
    const int m = f.model->input_size();
    DiscretizeOptions o;
    o.integrator.budget = std::move(budget);
    own = discretize(ltv_system(*f.model), times, Eigen::MatrixXd::Zero(m, m), o);
    if (!own.ok()) {
      TvlqrResult r;
      r.status = TvlqrResult::Status::IntegrationFailed;
      r.message = own.message;
      return r;
    }
    model = &own;
  }
  const Eigen::MatrixXd Q = vibration_weight(f.body, st.weight_elastic, st.weight_rigid_position, st.weight_rigid_rate);
  const Eigen::MatrixXd R = st.input_weights.asDiagonal();
  return solve_discrete_tvlqr(*model, Q, R, continuous.Qf);
}

MetricTargets targets(const Design& design, const Flight& f) {
  MetricTargets t;
  const RigidState end = f.nominal->at(Instant::at(design.controller->simulate_until_s));
  t.R_target = end.pos.head<2>();
  t.theta_target = end.pos(2);
  return t;
}

}  // namespace detail

LqgStudyResult run_lqg_study(const Design& design, const SuppressionStudyResult& suppression,
                             const ManeuverStudyResult* maneuver, const StudyLog& log) {
  LqgStudyResult r;
  const LqgStudy& lq = *design.lqg;
  auto fail = [&](const std::string& why) { fail_study(r, log, why); };
  if (!suppression.chain.law.ok() || !suppression.chain.nominal) {
    fail("[lqg]: the [controller]'s TV-LQR is not available (" + suppression.chain.message + ")");
    return r;
  }
  r.open_loop_energy_J = detail::main_chain_energy(suppression, "open_loop");
  r.continuous_energy_J = detail::main_chain_energy(suppression, "tvlqr");
  const detail::Flight f(design, suppression, maneuver);
  // the filter's and the digital law's discretizations, the three flights and their error
  // estimates share one work budget
  const auto budget = std::make_shared<WorkBudget>(design.study_work, "the [lqg] study");
  if (log.log) *log.log << "lqg: Kalman filter at " << lq.sample_rate_hz << " Hz ... " << std::flush;
  r.filter = detail::design_filter(design, f, budget);
  if (log.log) *log.log << (r.filter.ok() ? "done" : "FAILED") << '\n';
  if (!r.filter.ok()) {
    fail("[lqg]: the Kalman filter failed: " + r.filter.message);
    r.work_units = budget->spent();
    return r;
  }
  r.final_elastic_std = r.filter.P_post.back().diagonal().segment(3, f.body.n()).cwiseSqrt();
  SampledLoopOptions so;
  so.sample_rate_hz = lq.sample_rate_hz;
  so.t_end = design.controller->simulate_until_s;
  so.limits = design.controller->limits;
  so.delay_known = lq.delay_known;
  so.integrator.budget = budget;
  // the plant's integration between samples: Adams at the [controller]'s closed-loop tolerances
  so.integrator.rtol = design.controller->closed_loop_rtol;
  so.integrator.atol = design.controller->closed_loop_atol;
  const double out_step = 0.005;  // the [controller]'s comparison step
  const double ratio = out_step * lq.sample_rate_hz;
  so.output_step_s = std::abs(ratio - std::round(ratio)) < 1e-9 && ratio >= 1.0 ? out_step : 0.0;
  const MetricTargets tg = detail::targets(design, f);
  if (log.log) *log.log << "lqg: digital TV-LQR at " << lq.sample_rate_hz << " Hz ... " << std::flush;
  r.digital_law = detail::design_digital_law(design, f, suppression.chain.law, lq.sample_rate_hz, budget, &r.filter.model);
  if (log.log) *log.log << (r.digital_law.ok() ? "done" : "FAILED") << '\n';
  if (!r.digital_law.ok()) {
    fail("[lqg]: the digital TV-LQR failed: " + r.digital_law.message);
    r.work_units = budget->spent();
    return r;
  }
  using FB = SampledLoopOptions::Feedback;
  const std::vector<std::pair<std::string, FB>> cases{
      {"tvlqr_sampled", FB::FullState}, {"digital_tvlqr", FB::FullState}, {"lqg", FB::Lqg}};
  r.work_budget_units = budget->total();
  std::vector<std::string> not_run;  // cases left out once the budget is spent
  // one flight; `tighten` divides the plant integration's rtol and atol (the filter, the
  // law and the noise stay: only the integration error changes)
  auto fly = [&](const std::string& name, FB feedback, double tighten) {
    SampledLoopOptions sk = so;
    sk.feedback = feedback;
    if (feedback == FB::FullState) sk.delay_known = false;
    sk.integrator.rtol /= tighten;
    sk.integrator.atol /= tighten;
    const TvlqrResult& law = name == "tvlqr_sampled" ? suppression.chain.law : r.digital_law;
    return simulate_sampled_loop(f.body, *f.model, f.loads, f.u0, law, &r.filter, design.sensors, lq.plant, sk);
  };
  for (const auto& [name, feedback] : cases) {
    if (budget->exhausted()) {
      not_run.push_back(name);
      continue;
    }
    if (log.log) *log.log << "lqg: " << name << " on the full model ... " << std::flush;
    LqgStudyResult::Case c;
    c.name = name;
    c.run = fly(name, feedback, 1.0);
    if (log.log) *log.log << (c.run.ok() ? "done" : "FAILED") << " (" << std::fixed << std::setprecision(2)
                          << c.run.wall_time_s << " s)" << std::defaultfloat << '\n';
    if (!c.run.ok()) {
      fail("[lqg]: " + name + ": " + c.run.message);
      continue;
    }
    c.metrics = response_metrics(f.body, c.run.t, c.run.z, c.run.z_dot, c.run.commands, tg);
    r.cases.push_back(std::move(c));
  }
  // Each flight again at 10x tighter tolerances: how far its energy is from converged.
  // Energies below 1e-10 of the open loop's are zero to the integration's accuracy.
  if (lq.error_estimate && !r.cases.empty()) {
    if (log.log) *log.log << "lqg: the flights at 10x tighter tolerances, for the error estimate ... " << std::flush;
    const double floor = 1e-10 * r.open_loop_energy_J;
    std::string failed;
    for (auto& c : r.cases) {
      if (budget->exhausted()) {
        not_run.push_back("the error estimate of " + c.name);
        continue;
      }
      const FB feedback = c.name == "lqg" ? FB::Lqg : FB::FullState;
      const SampledLoopResult again = fly(c.name, feedback, 10.0);
      if (!again.ok()) {
        if (budget->exhausted())
          not_run.push_back("the error estimate of " + c.name + " (stopped)");
        else
          failed += (failed.empty() ? "" : "; ") + c.name + ": " + again.message;
        continue;
      }
      const ResponseMetrics m = response_metrics(f.body, again.t, again.z, again.z_dot, again.commands, tg);
      const double e = c.metrics.residual_vibration_energy_J;
      c.energy_error_estimate_J = std::abs(m.residual_vibration_energy_J - e);
      if (detail::energy_not_converged(c.energy_error_estimate_J, e, floor)) {
        std::ostringstream os;
        os << "[lqg]: the " << c.name << " residual vibration energy " << e << " J moves by "
           << c.energy_error_estimate_J << " J at 10x tighter tolerances: not converged; tighten [controller] "
              "closed_loop_rtol/closed_loop_atol";
        r.warnings.push_back(os.str());
        if (log.warn) log.warn(r.warnings.back());
      }
    }
    if (log.log) *log.log << (failed.empty() ? "done" : "some did not complete") << '\n';
    if (!failed.empty()) {
      r.warnings.push_back("[lqg]: no error estimate for " + failed);
      if (log.warn) log.warn(r.warnings.back());
    }
  }
  if (!not_run.empty()) {
    std::string list;
    for (const auto& w : not_run) list += (list.empty() ? "" : ", ") + w;
    fail("[lqg]: " + budget->spent_message() + ": not run: " + list);
  }
  r.work_units = budget->spent();
  if (log.log) {
    *log.log << "  case               E_vib(end) [J]  mean, last 1 s [J]  error estimate [J]\n";
    *log.log << "  open_loop          " << std::setw(14) << std::setprecision(4) << r.open_loop_energy_J << '\n';
    *log.log << "  tvlqr_continuous   " << std::setw(14) << r.continuous_energy_J << '\n';
    for (const auto& c : r.cases)
      *log.log << "  " << std::left << std::setw(19) << c.name << std::right << std::setw(14)
               << c.metrics.residual_vibration_energy_J << std::setw(20) << c.metrics.mean_vibration_energy_J
               << std::setw(20) << c.energy_error_estimate_J << '\n';
  }
  return r;
}

// ---------------------------------------------------------------------------------------
// Sweeps

namespace {

/// splitmix64's finalizer: decorrelates (seed, index, stream) into a seed.
std::uint64_t mix(std::uint64_t a, std::uint64_t b) {
  std::uint64_t z = a * 0x9e3779b97f4a7c15ULL + b + 0x632be59bd9b4e019ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// A uniform number in [0, 1) from the stream's normal pair: Φ would cost more; the
/// parameters' uniform draws come from their own splitmix64 stream instead.
double uniform01(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return std::nan("");
  const double x = p * static_cast<double>(sorted.size() - 1);
  const std::size_t i = static_cast<std::size_t>(std::floor(x));
  const double frac = x - static_cast<double>(i);
  return i + 1 < sorted.size() ? sorted[i] + frac * (sorted[i + 1] - sorted[i]) : sorted[i];
}

constexpr int kMetricFields = 5;  // residual, mean, peak tip, attitude error, position error

std::string hex(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%a", v);
  return buf;
}

std::string journal_header(const Design& d) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "freeflex sweep journal 1 design %016" PRIx64 " samples %ld", d.digest,
                d.sweep->total_samples());
  return std::string(buf) + " freeflex " + version();  // another version may compute other bits
}

std::string journal_line(const SweepSample& s) {
  std::ostringstream os;
  os << s.index << ' ' << (s.ok ? 1 : 0);
  for (double v : s.values) os << ' ' << hex(v);
  const ResponseMetrics& m = s.metrics;
  for (double v : {m.residual_vibration_energy_J, m.mean_vibration_energy_J, m.peak_tip_deflection_m,
                   m.final_attitude_error_rad, m.final_position_error_m, m.peak_command, s.wall_time_s})
    os << ' ' << hex(v);
  os << " end\n";
  return os.str();
}

/// The finished samples of a journal written for this design (none if absent or for
/// another design); a line cut short by a kill is ignored.
std::vector<SweepSample> read_journal(const std::string& path, const Design& d, std::size_t parameters) {
  std::vector<SweepSample> out;
  std::ifstream in(path);
  if (!in) return out;
  std::string line;
  if (!std::getline(in, line) || line != journal_header(d)) return out;
  while (std::getline(in, line)) {
    std::istringstream is(line);
    SweepSample s;
    int ok = 0;
    if (!(is >> s.index >> ok)) continue;
    std::vector<double> v;
    std::string tok;
    while (is >> tok && tok != "end") v.push_back(std::strtod(tok.c_str(), nullptr));
    if (tok != "end" || v.size() != parameters + kMetricFields + 2) continue;
    if (s.index < 0 || s.index >= d.sweep->total_samples()) continue;
    s.ok = ok == 1;
    s.values.assign(v.begin(), v.begin() + static_cast<long>(parameters));
    std::size_t k = parameters;
    s.metrics.residual_vibration_energy_J = v[k++];
    s.metrics.mean_vibration_energy_J = v[k++];
    s.metrics.peak_tip_deflection_m = v[k++];
    s.metrics.final_attitude_error_rad = v[k++];
    s.metrics.final_position_error_m = v[k++];
    s.metrics.peak_command = v[k++];
    s.wall_time_s = v[k++];
    out.push_back(s);
  }
  return out;
}

}  // namespace

std::vector<double> sweep_sample_values(const SweepStudy& sw, long index) {
  std::vector<double> v;
  std::uint64_t state = mix(sw.seed, static_cast<std::uint64_t>(index));
  NormalStream normal(mix(state, 1));
  long grid = index / sw.samples;
  for (const SweepParameter& p : sw.parameters) {
    switch (p.kind) {
      case SweepParameter::Kind::Uniform: v.push_back(p.a + (p.b - p.a) * uniform01(state)); break;
      case SweepParameter::Kind::Normal: {
        double x = p.a + p.b * normal.next();
        x = std::max(x, p.a - 5.0 * p.b);  // the reader keeps mean - 5 std inside the bounds
        v.push_back(x);
        break;
      }
      case SweepParameter::Kind::Grid: {
        const long i = grid % p.points;
        grid /= p.points;
        v.push_back(p.a + (p.b - p.a) * static_cast<double>(i) / (p.points - 1));
        break;
      }
    }
  }
  return v;
}

void validate(const SweepExecution& e) {
  if (e.threads < 0) throw std::invalid_argument("sweep execution: threads = " + std::to_string(e.threads) + ", must be >= 0");
  if (e.ranks < 1 || e.rank < 0 || e.rank >= e.ranks)
    throw std::invalid_argument("sweep execution: rank " + std::to_string(e.rank) + " of " + std::to_string(e.ranks) +
                                ", expected 0 <= rank < ranks");
  if (e.ranks > 1 && !e.gather) throw std::invalid_argument("sweep execution: ranks > 1 needs a gather function");
}

std::pair<double, double> wilson_interval(long successes, long n, double z) {
  if (n <= 0) return {0.0, 1.0};
  const double nn = static_cast<double>(n), p = static_cast<double>(successes) / nn, z2 = z * z;
  const double centre = (p + z2 / (2.0 * nn)) / (1.0 + z2 / nn);
  const double half = z / (1.0 + z2 / nn) * std::sqrt(p * (1.0 - p) / nn + z2 / (4.0 * nn * nn));
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

std::pair<double, double> quantile_interval(const std::vector<double>& sorted, double q, double z) {
  const double n = static_cast<double>(sorted.size()), spread = n * q * (1.0 - q);
  if (spread < 5.0) return {std::nan(""), std::nan("")};
  const double half = z * std::sqrt(spread);
  // 1-based ranks, clamped to the sample
  const long lo = std::max(1L, static_cast<long>(std::floor(n * q - half)));
  const long hi = std::min(static_cast<long>(sorted.size()), static_cast<long>(std::ceil(n * q + half)));
  return {sorted[static_cast<std::size_t>(lo - 1)], sorted[static_cast<std::size_t>(hi - 1)]};
}

SweepStudyResult run_sweep_study(const Design& design, const SuppressionStudyResult& suppression,
                                 const ManeuverStudyResult* maneuver, const SweepExecution& ex, const StudyLog& log) {
  validate(ex);
  const SweepStudy& sw = *design.sweep;
  SweepStudyResult r;
  for (const SweepParameter& p : sw.parameters) r.parameter_names.push_back(to_string(p.name));
  auto fail = [&](const std::string& why) { fail_study(r, log, why); };
  if (!suppression.chain.law.ok() || !suppression.chain.nominal) {
    fail("[sweep]: the [controller]'s TV-LQR is not available (" + suppression.chain.message + ")");
    return r;
  }
  const detail::Flight f(design, suppression, maneuver);
  const bool lqg = sw.feedback == SampledLoopOptions::Feedback::Lqg;
  const double rate = lqg ? design.lqg->sample_rate_hz : sw.sample_rate_hz;
  KalmanResult filter;
  // the filter and the digital law within a study's work budget; the samples share the
  // sweep's out equally (each at most a study's), so that a sample's result does not
  // depend on how many run beside it
  const auto setup = std::make_shared<WorkBudget>(design.study_work, "the [sweep] study's filter and digital law");
  const long total = sw.total_samples();
  const long long share = std::min(design.study_work, design.sweep_work / std::max(1L, total));
  std::atomic<long> out_of_work{0};  // samples flown here that spent their share
  std::atomic<long long> sample_work{0};
  r.work_share_per_sample = share;
  if (lqg) {
    filter = detail::design_filter(design, f, setup);
    if (!filter.ok()) {
      fail("[sweep]: the Kalman filter failed: " + filter.message);
      r.setup_work_units = setup->spent();
      return r;
    }
  }
  const TvlqrResult law =
      detail::design_digital_law(design, f, suppression.chain.law, rate, setup, lqg ? &filter.model : nullptr);
  r.setup_work_units = setup->spent();
  if (!law.ok()) {
    fail("[sweep]: the digital TV-LQR failed: " + law.message);
    return r;
  }
  const MetricTargets tg = detail::targets(design, f);
  r.samples.resize(static_cast<std::size_t>(total));

  // the journal: samples finished by an earlier, interrupted run of this design
  std::vector<char> done(static_cast<std::size_t>(total), 0);
  std::unique_ptr<std::ofstream> journal;
  std::mutex journal_mutex;
  if (!ex.journal.empty()) {
    for (SweepSample& s : read_journal(ex.journal, design, sw.parameters.size())) {
      const std::size_t i = static_cast<std::size_t>(s.index);
      if (done[i]) continue;
      done[i] = 1;
      r.samples[i] = std::move(s);
      ++r.resumed;
    }
    const bool fresh = r.resumed == 0;
    journal = std::make_unique<std::ofstream>(ex.journal, fresh ? std::ios::trunc : std::ios::app);
    if (!*journal) throw IoError("cannot write the sweep journal '" + ex.journal + "'");
    if (fresh) *journal << journal_header(design) << '\n' << std::flush;
  }
  std::vector<long> todo;
  for (long i = ex.rank; i < total; i += ex.ranks)
    if (!done[static_cast<std::size_t>(i)]) todo.push_back(i);

  // sample `index`; `tighten` divides the plant integration's rtol and atol; `budget`:
  // the work budget to charge (null: the sample's own share of the sweep's)
  auto fly = [&](long index, double tighten = 1.0, std::shared_ptr<WorkBudget> budget = nullptr,
                 std::string* why = nullptr) {
    const auto clock0 = std::chrono::steady_clock::now();
    SweepSample s;
    s.index = index;
    s.values = sweep_sample_values(sw, index);
    BeamProperties props = design.beam;
    std::vector<double> damping = design.damping_ratios;
    PlantOptions po = lqg ? design.lqg->plant : PlantOptions{};
    if (!lqg) po.measurement_noise = false;
    po.seed = mix(mix(sw.seed, static_cast<std::uint64_t>(index)), 2);
    for (std::size_t k = 0; k < sw.parameters.size(); ++k) {
      const double v = s.values[k];
      switch (sw.parameters[k].name) {
        case SweepParameter::Name::BendingStiffnessScale:
          for (auto& seg : props.segments) seg.bending_stiffness_Nm2 *= v;
          break;
        case SweepParameter::Name::MassScale:
          for (auto& seg : props.segments) seg.mass_per_length_kg_m *= v;
          break;
        case SweepParameter::Name::DampingRatio: damping.assign(static_cast<std::size_t>(f.body.n()), v); break;
        case SweepParameter::Name::ActuatorGain: po.actuator_gain = v; break;
        case SweepParameter::Name::DelayS: po.delay_s = v; break;
        case SweepParameter::Name::LagS: po.lag_s = v; break;
      }
    }
    try {
      const FlexibleBody plant(Beam(props), design.noa, design.basis, design.force_elements(), damping,
                               design.geometric_stiffening);
      SampledLoopOptions so;
      so.feedback = sw.feedback;
      so.sample_rate_hz = rate;
      so.t_end = design.controller->simulate_until_s;
      so.limits = design.controller->limits;
      so.delay_known = lqg && design.lqg->delay_known;
      so.output_step_s = 0.0;
      so.integrator.rtol = design.controller->closed_loop_rtol / tighten;
      so.integrator.atol = design.controller->closed_loop_atol / tighten;
      const bool own = !budget;
      so.integrator.budget =
          own ? std::make_shared<WorkBudget>(share, "sample " + std::to_string(index) + " of the [sweep] study") : budget;
      so.integrator.budget->charge(body_build_work(design));  // the plant built above
      const SampledLoopResult run = simulate_sampled_loop(plant, *f.model, f.loads, f.u0, law,
                                                          lqg ? &filter : nullptr, design.sensors, po, so);
      s.ok = run.ok();
      if (why) *why = run.message;
      if (own && !s.ok && so.integrator.budget->exhausted()) ++out_of_work;
      if (own) sample_work += so.integrator.budget->spent();
      if (s.ok) s.metrics = response_metrics(plant, run.t, run.z, run.z_dot, run.commands, tg);
    } catch (const std::invalid_argument& e) {
      s.ok = false;  // a sample the plant cannot be built for (cannot happen for read designs)
      if (why) *why = e.what();
    }
    if (!s.ok) {
      const double nan = std::nan("");
      s.metrics.residual_vibration_energy_J = s.metrics.mean_vibration_energy_J = nan;
    }
    s.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return s;
  };

  int threads = ex.threads > 0 ? ex.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = static_cast<int>(std::min<long>(threads, std::max<long>(1, static_cast<long>(todo.size()))));
  r.threads = threads;
  r.ranks = ex.ranks;
  if (log.log)
    *log.log << "sweep: " << total << " samples (" << todo.size() << " here, " << r.resumed << " from the journal), "
             << threads << " thread(s), " << ex.ranks << " rank(s) ... " << std::flush;
  const auto clock0 = std::chrono::steady_clock::now();
  std::atomic<std::size_t> next{0};
  std::atomic<long> finished{0};
  auto worker = [&]() {
    for (std::size_t j = next++; j < todo.size(); j = next++) {
      SweepSample s = fly(todo[j]);
      if (journal) {
        const std::string line = journal_line(s);
        std::lock_guard<std::mutex> lock(journal_mutex);
        *journal << line << std::flush;  // in the kernel's cache: survives the process being killed
      }
      r.samples[static_cast<std::size_t>(s.index)] = std::move(s);
      ++finished;
    }
  };
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(worker);
  worker();
  for (auto& t : pool) t.join();
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
  r.sample_work_units = sample_work;
  if (ex.ranks > 1) ex.gather(r.samples);
  double cpu = 0.0;
  for (long i : todo) cpu += r.samples[static_cast<std::size_t>(i)].wall_time_s;
  r.time_per_sample_s = todo.empty() ? 0.0 : r.wall_time_s / static_cast<double>(todo.size());
  r.cpu_time_per_sample_s = todo.empty() ? 0.0 : cpu / static_cast<double>(todo.size());
  if (log.log) *log.log << "done (" << std::fixed << std::setprecision(2) << r.wall_time_s << " s, "
                        << std::setprecision(4) << r.time_per_sample_s << " s per sample)" << std::defaultfloat << '\n';

  // statistics in sample order
  std::vector<double> energies;
  long meeting = 0;
  double sum = 0.0;
  for (const SweepSample& s : r.samples) {
    if (s.index < 0) continue;
    if (!s.ok) {
      ++r.failed;
      continue;
    }
    ++r.completed;
    const double e = s.metrics.residual_vibration_energy_J;
    energies.push_back(e);
    sum += e;
    meeting += e <= sw.requirement_energy_J;
  }
  std::vector<double> sorted = energies;
  std::sort(sorted.begin(), sorted.end());
  r.mean_J = energies.empty() ? std::nan("") : sum / static_cast<double>(energies.size());
  r.p05_J = percentile(sorted, 0.05);
  r.p50_J = percentile(sorted, 0.50);
  r.p95_J = percentile(sorted, 0.95);
  r.worst_J = sorted.empty() ? std::nan("") : sorted.back();
  r.fraction_meeting = static_cast<double>(meeting) / static_cast<double>(total);
  std::tie(r.fraction_meeting_low, r.fraction_meeting_high) = wilson_interval(meeting, total);
  std::tie(r.p95_low_J, r.p95_high_J) = quantile_interval(sorted, 0.95);
  if (sw.error_estimate && !sorted.empty()) {
    // The integration's share: the samples at the median, the 95th percentile, the worst and
    // the nearest the requirement (by rank of (energy, index): every thread and rank picks
    // the same) flown again at 10x tighter tolerances, charged to the study's budget.
    // Changes below 1e-10 of the open loop's energy are zero to the integration's accuracy.
    const double floor = 1e-10 * detail::main_chain_energy(suppression, "open_loop");
    std::vector<std::pair<double, long>> ranked;
    for (const SweepSample& s : r.samples)
      if (s.index >= 0 && s.ok) ranked.push_back({s.metrics.residual_vibration_energy_J, s.index});
    std::sort(ranked.begin(), ranked.end());
    const std::size_t last = ranked.size() - 1;
    // and the sample nearest the requirement (in log E): the verdict most at risk
    std::size_t nearest = 0;
    for (std::size_t k = 1; k < ranked.size(); ++k)
      if (std::abs(std::log(ranked[k].first / sw.requirement_energy_J)) <
          std::abs(std::log(ranked[nearest].first / sw.requirement_energy_J)))
        nearest = k;
    const std::pair<const char*, std::size_t> roles[] = {
        {"median", last / 2},
        {"p95", static_cast<std::size_t>(std::floor(0.95 * static_cast<double>(last)))},
        {"worst", last},
        {"nearest_requirement", nearest}};
    if (log.log)
      *log.log << "sweep: the median, p95, worst and nearest-the-requirement samples at 10x tighter tolerances ... "
               << std::flush;
    double worst_rel = -1.0;
    for (const auto& [role, k] : roles) {
      const long index = ranked[k].second;
      if (std::any_of(r.error_checks.begin(), r.error_checks.end(), [&](const auto& c) { return c.index == index; }))
        continue;
      SweepStudyResult::ErrorCheck c;
      c.role = role;
      c.index = index;
      c.energy_J = ranked[k].first;
      if (setup->exhausted()) {
        c.message = "not flown: " + setup->spent_message();
      } else {
        std::string why;
        const SweepSample again = fly(index, 10.0, setup, &why);
        if (again.ok) {
          c.tight_energy_J = again.metrics.residual_vibration_energy_J;
          if (c.energy_J > 0.0) worst_rel = std::max(worst_rel, std::abs(c.tight_energy_J - c.energy_J) / c.energy_J);
        } else {
          c.message = why.empty() ? "the flight failed" : why;
        }
      }
      r.error_checks.push_back(c);
    }
    r.setup_work_units = setup->spent();
    if (worst_rel >= 0.0) r.max_relative_error_estimate = worst_rel;
    if (log.log) *log.log << "done\n";
    for (const auto& c : r.error_checks) {
      std::ostringstream os;
      if (!std::isfinite(c.tight_energy_J)) {
        os << "[sweep]: no error estimate from the " << c.role << " sample " << c.index << ": " << c.message;
      } else {
        const bool meets = c.energy_J <= sw.requirement_energy_J, tight_meets = c.tight_energy_J <= sw.requirement_energy_J;
        const bool moved = detail::energy_not_converged(std::abs(c.tight_energy_J - c.energy_J), c.energy_J, floor);
        if (!moved && meets == tight_meets) continue;
        os << "[sweep]: the " << c.role << " sample " << c.index << "'s residual vibration energy " << c.energy_J
           << " J moves to " << c.tight_energy_J << " J at 10x tighter tolerances";
        if (meets != tight_meets)
          os << ": it " << (meets ? "meets" : "misses") << " the requirement (" << sw.requirement_energy_J << " J) as flown and "
             << (tight_meets ? "meets" : "misses") << " it when converged further; tighten [controller] closed_loop_rtol/closed_loop_atol";
        else
          os << ": not converged to 10%, though both "
             << (meets ? "meet" : "miss") << " the requirement (" << sw.requirement_energy_J << " J)";
      }
      r.warnings.push_back(os.str());
      if (log.warn) log.warn(r.warnings.back());
    }
  }
  if (r.failed > 0)
    fail("[sweep]: " + std::to_string(r.failed) + " of " + std::to_string(total) + " samples failed" +
         (out_of_work > 0 ? "; " + std::to_string(out_of_work.load()) + " of them spent their share of the sweep's work "
                            "budget (" + std::to_string(share) + " units each: " + std::to_string(design.sweep_work) +
                            " over " + std::to_string(total) + " samples, at most a study's " +
                            std::to_string(design.study_work) + "; README, the \"(limits)\" row)"
                          : std::string()));
  if (log.log)
    *log.log << "  residual vibration energy [J]: mean " << std::setprecision(4) << r.mean_J << ", p5 " << r.p05_J
             << ", median " << r.p50_J << ", p95 " << r.p95_J << ", worst " << r.worst_J << "; meeting <= "
             << sw.requirement_energy_J << " J: " << r.fraction_meeting * 100.0 << "% (95% confidence "
             << r.fraction_meeting_low * 100.0 << " .. " << r.fraction_meeting_high * 100.0 << "% from "
             << total << " samples)\n";
  return r;
}

}  // namespace freeflex
