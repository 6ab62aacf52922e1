// [maneuver]: the rigid maneuver to optimize (actuators, boundary states, objective,
// duration) and how (transcription, mesh, Ipopt and its options).
#include <algorithm>
#include <cmath>
#include <sstream>
#include <limits>

#include "io/design_sections.hpp"
#include "trajopt/ipopt_options.hpp"

namespace freeflex::io_detail {
namespace {

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

using Kind = Section::RawEntry::Kind;

/// Unknowns of the NLP on a mesh of `intervals` (trajopt's CollocationNlp layout): the states and
/// the controls at each point, the compressed form's midpoint controls, the free duration.
double nlp_unknowns(const ManeuverStudy& st, int intervals, int noa) {
  const double N = intervals, nu = static_cast<double>(st.problem.actuators.size());
  const Transcription tr = st.options.transcription;
  const double points = tr == Transcription::HermiteSimpson ? 2 * N + 1 : N + 1;
  // the rigid state, and with `elastic` the first-order state x1 (trajopt/elastic_dynamics.hpp)
  const int modes = st.problem.elastic_modes > 0 ? st.problem.elastic_modes : noa;
  const double states = 6 + (st.problem.elastic ? 4 + 2 * modes : 0);
  return points * (states + nu) + (tr == Transcription::HermiteSimpsonCompressed ? N * nu : 0) +
         (st.problem.free_time ? 1 : 0);
}

/// Collocation points of a mesh of `intervals` (states and controls at each).
double nlp_points(const ManeuverStudy& st, int intervals) {
  return st.options.transcription == Transcription::HermiteSimpson ? 2.0 * intervals + 1 : intervals + 1.0;
}

/// Unknowns at each point: the states (with `elastic` the first-order state too) and the controls.
double point_unknowns(const ManeuverStudy& st, int noa) {
  const int modes = st.problem.elastic_modes > 0 ? st.problem.elastic_modes : noa;
  return 6.0 + (st.problem.elastic ? 4.0 + 2.0 * modes : 0.0) + static_cast<double>(st.problem.actuators.size());
}

/// [maneuver.ipopt]: every entry checked against Ipopt's own registry (name, type, bounds,
/// valid strings) and against what this build and freeflex allow, all at once, before any
/// work. The derivative checker becomes TrajoptOptions::derivative_test (first mesh round
/// only, its verdict counted); the rest is passed to Ipopt as written.
void read_ipopt_options(Section& m, ManeuverStudy& st, Outputs& outputs, int noa) {
  Section ip = m.table("ipopt");
  if (!ip.present()) return;
  TrajoptOptions& o = st.options;
  for (const auto& e : ip.raw_entries()) {
    const std::string& key = e.key;
    const std::string value = trimmed(e.text);
    const std::string shown = e.kind == Kind::String || e.kind == Kind::Boolean ? "\"" + e.text + "\"" : e.text;
    const std::string lead = ip.key_path(key) + " = " + (e.kind == Kind::Boolean ? (e.text == "yes" ? "true" : "false") : shown);
    const detail::OptionText kind = e.kind == Kind::String    ? detail::OptionText::String
                                    : e.kind == Kind::Integer ? detail::OptionText::Integer
                                    : e.kind == Kind::Float   ? detail::OptionText::Number
                                                              : detail::OptionText::Boolean;
    if (key == "option_file_name") {
      ip.problem(key, lead + ": options files are not read; give each option in [maneuver.ipopt], where it is checked");
      continue;
    }
    const std::string why = detail::ipopt_option_problem(key, value, kind);
    if (!why.empty()) {
      ip.problem(key, why.rfind("must", 0) == 0 ? lead + ", " + why : lead + " " + why);
      continue;
    }
    // the factorization is freeflex's choice ([maneuver] linear_solver): any other Ipopt
    // solver makes Debian's Ipopt abort the whole process (it tries to load libhsl.so)
    if (key == "linear_solver") {
      ip.problem(key, lead + ": choose the factorization with maneuver.linear_solver = \"ldlt\" or \"mumps\"");
      continue;
    }
    if (key == "linear_system_scaling" && lower_trimmed(value) == "mc19") {
      ip.problem(key, lead + ", must be \"none\" or \"slack-based\" (MC19 is part of HSL, which this Ipopt lacks)");
      continue;
    }
    // freeflex writes Ipopt's log there, into the run's directory with the other results
    // (and replaced with them), so it must be a plain file name.
    if (key == "output_file") {
      if (!plain_name(e.text, ".")) {
        ip.problem(key, lead +
                            ", must be a file name of 1 to 64 letters, digits, '_', '-' or '.', not starting with "
                            "'.' (Ipopt writes it into the output directory)");
        continue;
      }
      outputs.named(ip, key, e.text, {""});
    }
    if (key == "max_iter" && std::stoll(value) > lim::kMaxIterations) {  // the registry allowed it: an integer
      ip.problem(key, lead + ", must be at most " + std::to_string(lim::kMaxIterations) + " (the supported range)");
      continue;
    }
    if (key == "derivative_test") {  // freeflex runs the checker on the first mesh only and counts its errors
      const std::string test = lower_trimmed(value);
      // the checker's work grows like n^3 (first order) or faster (second order) in the
      // NLP's unknowns, and it prints nothing until it ends: bound n
      const double n = nlp_unknowns(st, o.intervals, noa);
      const double most = test == "first-order" ? lim::kMaxDerivativeTestUnknowns : lim::kMaxSecondOrderTestUnknowns;
      if (test != "none" && n > most) {
        ip.problem(key, lead + " with maneuver.intervals = " + std::to_string(o.intervals) + " tests " +
                            std::to_string(static_cast<long long>(n)) + " NLP unknowns; at most " +
                            std::to_string(static_cast<long long>(most)) +
                            " for this test: check the derivatives on fewer intervals (they do not depend on the mesh)");
        continue;
      }
      o.derivative_test = test;
      continue;
    }
    o.ipopt_options.emplace_back(key, e.text);
  }
}

/// The optimizer's work, bounded before any work: Ipopt iterations x NLP unknowns, summed
/// over the mesh-refinement rounds (each round's mesh at most doubles, up to
/// max_intervals). Reported at the first of max_iterations, intervals, mesh_refinements
/// the file gives.
void check_ipopt_work(Section& m, const ManeuverStudy& st, int noa) {
  const TrajoptOptions& o = st.options;
  if (st.problem.actuators.empty()) return;  // the actuators' problem is reported
  long long iterations = o.max_iter;
  std::string iterations_key = "max_iterations";
  for (const auto& [key, value] : o.ipopt_options)
    if (key == "max_iter") {
      iterations = std::stoll(value);  // checked against Ipopt's registry: a whole number
      iterations_key = "ipopt.max_iter";
    }
  // An elastic maneuver's derivatives (dense first-order blocks) cost like s³/100 - 4 s
  // more unknowns at each point of s unknowns, nothing below s = 20 (fitted to 3.6 µs per
  // unknown and iteration at s = 16, 8 to 13 ms a point and iteration at s = 71, 35 ms at
  // 131, 0.1 to 0.24 s at 211), Ipopt's matrices hold about 20 s² doubles a point, and the
  // rigid counterpart is solved before it (its starting point) with the same options.
  const bool elastic = st.problem.elastic;
  ManeuverStudy rigid = st;
  rigid.problem.elastic = false;
  const double s = point_unknowns(st, noa);
  double unknowns = 0, derivatives = 0, rigid_unknowns = 0, largest = 0;
  for (int r = 0, n = o.intervals; r <= o.mesh_refinements; ++r, n = std::min(2 * n, o.max_intervals)) {
    unknowns += nlp_unknowns(st, n, noa);
    if (!elastic) continue;
    derivatives += nlp_points(st, n) * std::max(0.0, s * s * s / 100.0 - 4.0 * s);
    rigid_unknowns += nlp_unknowns(rigid, n, noa);
    largest = std::max(largest, nlp_points(st, n) * s * s);
  }
  std::string at = "intervals";
  for (const char* k : {"max_iterations", "intervals", "mesh_refinements"})
    if (m.has(k)) {
      at = k;
      break;
    }
  if (largest > lim::kMaxElasticNlpSize) {
    std::string where = "intervals";
    for (const char* k : {"intervals", "mesh_refinements", "elastic_modes"})
      if (m.has(k)) {
        where = k;
        break;
      }
    std::ostringstream os;
    os << m.key_path("intervals") << " = " << o.intervals << " with mesh_refinements = " << o.mesh_refinements
       << " gives an elastic NLP of up to " << show_count(largest / (s * s)) << " collocation points of " << shortest(s)
       << " unknowns each (states and controls): points x unknowns² = " << show_count(largest) << "; at most "
       << shortest(lim::kMaxElasticNlpSize) << " (about 400 MB of Ipopt's matrices): fewer intervals or "
       << "mesh_refinements, or fewer elastic_modes";
    m.problem(where, os.str());
    return;
  }
  // the coarse start (TrajoptOptions::coarse_start): the rigid problem (or, for an elastic
  // one, its rigid counterpart's own) on max(10, N/8) intervals, at most 500 iterations
  double coarse = 0.0, coarse_unknowns = 0.0;
  const int nc = o.coarse_start_intervals();
  if (o.coarse_start && nc < o.intervals && iterations > 0) {
    coarse_unknowns = nlp_unknowns(rigid, nc, noa);
    coarse = coarse_unknowns *
             static_cast<double>(std::min<long long>(iterations, TrajoptOptions::coarse_start_max_iter)) /
             static_cast<double>(iterations);
  }
  const double work = static_cast<double>(iterations) * (unknowns + derivatives + rigid_unknowns + coarse);
  if (work <= lim::kMaxIpoptWork) return;
  std::ostringstream os;
  os << m.key_path(iterations_key) << " = " << iterations << " with intervals = " << o.intervals
     << " and mesh_refinements = " << o.mesh_refinements << " allows " << show_count(std::ceil(work))
     << " Ipopt iteration-unknowns (iterations x NLP unknowns, " << shortest(unknowns) << " unknowns over the rounds";
  if (coarse > 0.0)
    os << ", the coarse start's " << shortest(coarse_unknowns) << " for at most " << TrajoptOptions::coarse_start_max_iter
       << " iterations (coarse_start = false drops it)";
  if (elastic)
    os << ", the elastic derivatives counted as " << show_count(std::ceil(derivatives))
       << " more (s³/100 - 4 s at each point of s = " << shortest(s) << " unknowns) and the rigid counterpart's "
       << shortest(rigid_unknowns);
  os << "); at most " << shortest(lim::kMaxIpoptWork)
     << " (about 3 min of CPU): lower max_iterations, intervals or mesh_refinements"
     << (elastic ? ", or elastic_modes" : "");
  m.problem(at, os.str());
}

}  // namespace

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
  p.t_min_s = duration("duration_min_s", false, p.t_min_s);
  p.t_max_s = duration("duration_max_s", false, p.t_max_s);
  // a free duration starts in the middle of its bounds
  p.duration_s = duration("duration_s", !p.free_time, 0.5 * (p.t_min_s + p.t_max_s));
  p.w_energy = objective == "energy" ? 1.0 : 0.0;
  p.w_time = objective == "time" ? 1.0 : 0.0;
  p.w_smooth = objective == "smooth" ? 1.0 : 0.0;
  if (objective == "weighted") {
    p.w_energy = m.number("energy_weight", kWeight, false).value_or(0.0);
    p.w_time = m.number("time_weight", kWeight, false).value_or(0.0);
    p.w_smooth = m.number("smooth_weight", kWeight, false).value_or(0.0);
  } else {
    for (const char* k : {"energy_weight", "time_weight", "smooth_weight"})
      if (m.has(k)) m.problem(k, m.key_path(k) + " applies to objective = \"weighted\" only");
    for (const char* k : {"energy_weight", "time_weight", "smooth_weight"}) m.number(k, Range(), false);
  }
  // Optional arrays with one entry per actuator (their sizes are the library's check).
  auto per_actuator = [&](const char* key, const Range& range, auto& target) {
    if (auto v = m.number_array(key, range, false))
      target = Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v->data(), static_cast<Eigen::Index>(v->size())));
  };
  per_actuator("actuator_weights", kWeight, p.energy_weights);
  per_actuator("rate_limits", kCommand, p.du_max);
  // The elastic modes inside the problem (first-order model about the rigid motion).
  p.elastic = m.boolean("elastic", false).value_or(false);
  p.zero_end_commands = m.boolean("zero_end_commands", false).value_or(false);
  p.elastic_modes = static_cast<int>(
      m.integer_or_word("elastic_modes", 1, kMaxNoa, "all", ManeuverProblem::all_modes, false).value_or(-1));
  p.modes_at_rest = static_cast<int>(
      m.integer_or_word("modes_at_rest", 0, kMaxNoa, "all", ManeuverProblem::all_modes, false).value_or(0));
  p.w_vibration = m.number("vibration_weight", kWeight, false).value_or(0.0);
  p.tip_deflection_limit_m =
      m.number("tip_deflection_limit_m", Range::positive().supported(0.0, lim::kMaxPosition_m), false)
          .value_or(ManeuverProblem::inf);
  if (p.elastic && p.modes_at_rest > d.noa && d.noa > 0)
    m.problem("modes_at_rest", m.key_path("modes_at_rest") + " = " + std::to_string(p.modes_at_rest) +
                                   ", must be at most model.noa = " + std::to_string(d.noa) +
                                   " (the elastic coordinates) or \"all\"");
  if (p.elastic && p.elastic_modes > d.noa && d.noa > 0)
    m.problem("elastic_modes", m.key_path("elastic_modes") + " = " + std::to_string(p.elastic_modes) +
                                   ", must be at most model.noa = " + std::to_string(d.noa) +
                                   " (the elastic coordinates) or \"all\"");
  // What the library checks itself (bounds in order, weights, time weight and a free
  // duration, sizes per actuator) is reported at the keys that set it.
  FieldKeys keys{{"t_min_s", "duration_min_s"}, {"t_max_s", "duration_max_s"}, {"free_time", "free_duration"}};
  if (m.has("duration_s")) keys.emplace_back("duration_s", "duration_s");
  if (objective == "weighted")
    keys.insert(keys.end(), {{"w_energy", "energy_weight"}, {"w_time", "time_weight"}, {"w_smooth", "smooth_weight"}});
  if (names_ok) keys.insert(keys.end(), {{"energy_weights", "actuator_weights"}, {"du_max", "rate_limits"}});
  keys.insert(keys.end(), {{"modes_at_rest", "modes_at_rest"},
                           {"elastic_modes", "elastic_modes"},
                           {"w_vibration", "vibration_weight"},
                           {"tip_deflection_limit_m", "tip_deflection_limit_m"}});
  report_field_problems(m, problems(p, static_cast<int>(d.loads.size() + d.actuators.size())), keys);

  o.transcription = m.enumerated<Transcription>("transcription", false).value_or(o.transcription);
  o.linear_solver = m.enumerated<LinearSolver>("linear_solver", false).value_or(o.linear_solver);
  o.intervals = static_cast<int>(m.integer("intervals", 1, lim::kMaxIntervals, false).value_or(o.intervals));
  o.mesh_refinements =
      static_cast<int>(m.integer("mesh_refinements", 0, lim::kMaxMeshRefinements, false).value_or(o.mesh_refinements));
  o.mesh_tolerance = m.number("mesh_tolerance", Range::positive(), false).value_or(o.mesh_tolerance);
  o.coarse_start = m.boolean("coarse_start", false).value_or(o.coarse_start);
  o.tol = m.number("tolerance", Range{0.0, 1.0, true, true}, false).value_or(o.tol);
  o.max_iter = static_cast<int>(m.integer("max_iterations", 1, lim::kMaxIterations, false).value_or(o.max_iter));
  st.quiet = m.boolean("quiet", false).value_or(st.quiet);
  read_ipopt_options(m, st, outputs, d.noa);
  check_ipopt_work(m, st, d.noa);
  m.finish();
  outputs.fixed("[maneuver]", "trajectory.csv");
  for (const char* f : {"maneuver_states.gp", "maneuver_states.png", "maneuver_controls.gp", "maneuver_controls.png"})
    outputs.fixed("[maneuver]", f);
  d.maneuver = st;
}

}  // namespace freeflex::io_detail
