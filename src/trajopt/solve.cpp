// Optimal rigid maneuvers (trajopt/solve.hpp): the mesh-refinement loop around one Ipopt
// solve per mesh, each warm-started from the interpolated solution of the last.
#include "freeflex/trajopt/solve.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "freeflex/trajopt/collocation.hpp"
#include "trajopt/ipopt_adapter.hpp"

namespace freeflex {

namespace {

/// Halves every interval whose error estimate exceeds tol.
std::vector<double> refine(const std::vector<double>& sigma, const Eigen::VectorXd& err, double tol) {
  std::vector<double> out;
  for (std::size_t k = 0; k < sigma.size(); ++k) {
    if (err(static_cast<Eigen::Index>(k)) > tol) {
      out.push_back(0.5 * sigma[k]);
      out.push_back(0.5 * sigma[k]);
    } else {
      out.push_back(sigma[k]);
    }
  }
  return out;
}

}  // namespace

namespace {
/// A solve's NLP and the bound multipliers it ended with: where the next mesh starts from.
struct MeshMultipliers {
  std::shared_ptr<const CollocationNlp> nlp;
  detail::BoundMultipliers z;
};
}  // namespace

/// `warm`: the first round starts from a near-optimal guess (Ipopt at mu_init 1e-6, as a
/// mesh-refinement round), with the bound multipliers of `from` when given (the same
/// problem solved on another mesh). `last`, when given, receives the last round's.
static TrajoptResult solve_maneuver_with(const FlexibleBody& body, const ManeuverProblem& problem,
                                         const TrajoptOptions& options, std::chrono::steady_clock::time_point start,
                                         bool warm = false, const MeshMultipliers* from = nullptr,
                                         MeshMultipliers* last = nullptr);

Eigen::VectorXd TrajoptResult::control_at(double t_s) const {
  if (!trajectory) return Eigen::VectorXd::Zero(u.cols());
  return trajectory->control_at(t_s);
}

TrajoptResult solve_maneuver(const FlexibleBody& body, const ManeuverProblem& problem, const TrajoptOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  validate(body, problem);
  validate(options);

  // The separated Hermite–Simpson KKT system of the elastic problem factors in time linear
  // in N with MUMPS' approximate minimum degree ordering, superlinear with the approximate
  // minimum fill that suits the rest (NOA 6, N = 400 / 800: 2x / 3x slower;
  // docs/benchmarks.md). A user's own mumps_pivot_order wins.
  TrajoptOptions tuned;
  const TrajoptOptions* opts = &options;
  if (problem.elastic && options.transcription == Transcription::HermiteSimpson &&
      std::none_of(options.ipopt_options.begin(), options.ipopt_options.end(),
                   [](const auto& kv) { return kv.first == "mumps_pivot_order"; })) {
    tuned = options;
    tuned.ipopt_options.insert(tuned.ipopt_options.begin(), {"mumps_pivot_order", "0"});
    opts = &tuned;
  }
  // A problem given no guess starts from a coarse solution: the rigid problem (a rigid
  // one itself, an elastic one its rigid counterpart) solved first on an eighth of the
  // mesh (TrajoptOptions::coarse_start_intervals). From the straight line Ipopt's early iterations need large Hessian
  // regularizations (δ_w of 1-100 for the slews of docs/benchmarks.md, each costing
  // extra factorizations); from the coarse optimum (then a quarter of the mesh) the rigid slew at N = 100 took 11-15 ms
  // instead of 26-28 (the coarse solve included), the elastic slew 11 iterations instead
  // of 19 and 35-45% less time. A rigid problem continues as a mesh-refinement round does
  // (mu_init 1e-6); an elastic one from the default barrier, its elastic state at rest.
  int warm_iterations = 0;
  std::shared_ptr<const CollocationTrajectory> warm;
  MeshMultipliers coarse;
  const int coarse_intervals = options.coarse_start_intervals();
  if (options.coarse_start && !options.guess.solution && !options.guess.control &&
      (problem.elastic || coarse_intervals < options.intervals)) {
    TrajoptOptions ro = options;
    ro.intervals = std::min(coarse_intervals, options.intervals);
    ro.mesh_refinements = 0;
    ro.derivative_test = "none";
    ro.verbose = false;
    ro.keep_log = false;
    constexpr int cap = TrajoptOptions::coarse_start_max_iter;
    ro.max_iter = std::min(options.max_iter, cap);
    for (auto& [key, value] : ro.ipopt_options)  // Ipopt's own max_iter wins over max_iter: cap it too
      if (key == "max_iter") value = std::to_string(std::min<long>(cap, std::strtol(value.c_str(), nullptr, 10)));
    ro.coarse_start = false;
    // a starting point, not a result: its optimum differs from the full mesh's by far more
    // than 1e-4 (the slew on 80 intervals: 5e-4 in the objective), so it is not polished
    ro.tol = std::max(options.tol, TrajoptOptions::coarse_start_tol);
    const TrajoptResult rr =
        solve_maneuver_with(body, problem.elastic ? rigid_counterpart(problem) : problem, ro, start, false, nullptr,
                            &coarse);
    warm_iterations = rr.iterations;
    if (rr.ok()) warm = rr.trajectory;
  }
  if (warm) {
    if (opts != &tuned) tuned = options;
    tuned.guess = InitialGuess{};
    tuned.guess.solution = warm;
    opts = &tuned;
  }
  const bool continued = warm && !problem.elastic;
  TrajoptResult res = solve_maneuver_with(body, problem, *opts, start, continued, continued ? &coarse : nullptr);
  res.warm_start_iterations = warm_iterations;
  res.warm_started = warm != nullptr;
  return res;
}

static TrajoptResult solve_maneuver_with(const FlexibleBody& body, const ManeuverProblem& problem,
                                         const TrajoptOptions& options, std::chrono::steady_clock::time_point start,
                                         bool warm, const MeshMultipliers* from, MeshMultipliers* last) {
  TrajoptResult res;
  res.transcription = options.transcription;
  res.linear_solver = options.linear_solver;
  std::vector<double> mesh(static_cast<std::size_t>(options.intervals), 1.0 / options.intervals);
  InitialGuess guess = options.guess;
  MeshMultipliers previous;  // the last round's, the next round's start
  if (from) previous = *from;
  for (int round = 0;; ++round) {
    const auto nlp_kept = std::make_shared<const CollocationNlp>(body, problem, options.transcription, mesh);
    const CollocationNlp& nlp = *nlp_kept;
    const Eigen::VectorXd w0 = initial_point(nlp, guess);
    const bool warm_round = round > 0 || warm;
    detail::BoundMultipliers z0;
    if (warm_round && previous.nlp && previous.z.lower.size()) {
      z0.lower = nlp.carried_bound_multipliers(*previous.nlp, previous.z.lower);
      z0.upper = nlp.carried_bound_multipliers(*previous.nlp, previous.z.upper);
    }
    const bool have_z0 = z0.lower.size() == nlp.num_variables() && z0.upper.size() == nlp.num_variables() &&
                         z0.lower.allFinite() && z0.upper.allFinite();
    detail::NlpSolve run =
        detail::solve_nlp_ipopt(nlp, w0, options, round == 0, warm_round, have_z0 ? &z0 : nullptr);
    previous = {nlp_kept, std::move(run.z)};
    if (round == 0 && options.derivative_test != "none")
      res.derivative_test_errors = detail::derivative_errors(run.log);
    res.log += run.log;
    res.status = run.status;
    res.message = run.message;
    res.iterations += run.iterations;
    res.intervals = nlp.intervals();
    MeshRound mr;
    mr.intervals = nlp.intervals();
    mr.iterations = run.iterations;
    res.mode_frequencies.resize(0);  // this round's, or none (no stale values from a round before)
    res.max_interval_s = 0.0;
    res.unresolved_modes.clear();
    if (run.w.size() == nlp.num_variables()) {
      const Eigen::VectorXd& w = run.w;
      res.objective = nlp.objective(w);
      res.duration_s = nlp.duration(w);
      res.max_defect = nlp.max_defect(w);
      res.trajectory = nlp.trajectory(w);
      res.max_error_estimate = res.trajectory->interval_errors().maxCoeff();
      res.t = res.trajectory->knot_times();
      res.x = res.trajectory->knot_states().leftCols<6>();
      res.x_elastic = res.trajectory->knot_states().rightCols(nlp.state_size() - 6);
      res.terminal_vibration_energy_J = nlp.terminal_vibration_energy(w);
      if (const ElasticDynamics* el = nlp.dynamics().elastic()) {
        res.mode_frequencies = el->mode_frequencies();
        for (Eigen::Index k = 0; k + 1 < res.t.size(); ++k)
          res.max_interval_s = std::max(res.max_interval_s, res.t(k + 1) - res.t(k));
        for (Eigen::Index j = 0; j < res.mode_frequencies.size(); ++j)
          if (res.mode_frequencies(j) * res.max_interval_s > TrajoptResult::max_resolved_omega_h)
            res.unresolved_modes.push_back(static_cast<int>(j));
        res.peak_tip_deflection_m = 0.0;
        for (int j = 0; j < nlp.num_points(); ++j) {
          const auto q = w.segment(nlp.point_offset(j) + 6 + el->q_index(), el->n());
          res.peak_tip_deflection_m =
              std::max({res.peak_tip_deflection_m, std::abs(el->phi_left().dot(q)), std::abs(el->phi_right().dot(q))});
        }
      }
      res.u = res.trajectory->knot_controls();
      const int N = nlp.intervals(), nu = nlp.dynamics().nu();
      // ∫ uᵀ W u dt of the commands as flown: 3-point Gauss–Legendre per interval is exact
      // for the piecewise-quadratic (or linear) controls.
      const Eigen::VectorXd W =
          problem.energy_weights.size() == nu ? problem.energy_weights : Eigen::VectorXd::Ones(nu);
      static const double gx[3] = {0.5 - 0.5 * 0.7745966692414834, 0.5, 0.5 + 0.5 * 0.7745966692414834};
      static const double gw[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
      res.control_energy = 0.0;
      for (int k = 0; k < N; ++k) {
        const double ta = res.t(k), h = res.t(k + 1) - ta;
        for (int g = 0; g < 3; ++g) {
          const Eigen::VectorXd u = res.trajectory->control_at(Instant{ta + gx[g] * h, ta + 0.5 * h});
          res.control_energy += gw[g] * h * u.dot(W.cwiseProduct(u));
        }
      }
      if (has_midpoints(options.transcription)) {
        CollocationNlp::Midpoints mid = nlp.midpoints(w);
        res.x_mid = mid.x.leftCols<6>();
        res.u_mid = std::move(mid.u);
        res.t_mid.resize(N);
        for (int k = 0; k < N; ++k) res.t_mid(k) = nlp.mid_fraction(k) * res.duration_s;
      } else {
        res.t_mid.resize(0);
        res.x_mid.resize(0, 6);
        res.u_mid.resize(0, nu);
      }
      mr.objective = res.objective;
      mr.max_defect = res.max_defect;
      mr.max_error_estimate = res.max_error_estimate;
    } else {
      res.trajectory.reset();
    }
    res.rounds.push_back(mr);

    if (!res.ok() || !res.trajectory || round >= options.mesh_refinements) break;
    const Eigen::VectorXd err = res.trajectory->interval_errors();
    if (err.maxCoeff() <= options.mesh_tolerance) break;
    std::vector<double> finer = refine(nlp.mesh_fractions(), err, options.mesh_tolerance);
    if (static_cast<int>(finer.size()) > options.max_intervals) {
      res.message += "; mesh refinement stopped: " + std::to_string(finer.size()) + " intervals would exceed max_intervals = " +
                     std::to_string(options.max_intervals);
      break;
    }
    mesh = std::move(finer);
    guess = InitialGuess{};
    guess.solution = res.trajectory;
  }
  if (last && res.ok()) *last = std::move(previous);  // a failed solve's multipliers start nothing
  res.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

FlownManeuver flown_maneuver(const TrajoptResult& result, const ManeuverProblem& problem) {
  if (!result.ok() || !result.trajectory)
    throw std::invalid_argument("flown_maneuver: the maneuver was not solved (" + result.message + ")");
  FlownManeuver m;
  m.motion = result.trajectory;
  m.actuators = problem.actuators;
  const std::shared_ptr<const CollocationTrajectory> traj = result.trajectory;
  m.commands = [traj](const Instant& at, Eigen::Ref<Eigen::VectorXd> u) { u = traj->control_at(at); };
  const Eigen::VectorXd& knots = traj->knot_times();
  m.breakpoints.assign(knots.data(), knots.data() + knots.size());
  m.duration_s = result.duration_s;
  return m;
}

std::string unresolved_modes_message(const TrajoptResult& r) {
  if (r.unresolved_modes.empty()) return "";
  const int first = r.unresolved_modes.front(), last = r.unresolved_modes.back();
  const double w0 = r.mode_frequencies(first), w1 = r.mode_frequencies(last), h = r.max_interval_s;
  const double T = r.duration_s > 0.0 ? r.duration_s : h * std::max<Eigen::Index>(1, r.t.size() - 1);
  // the longest interval that resolves omega, and the uniform mesh over T it takes
  auto h_for = [](double omega) { return TrajoptResult::max_resolved_omega_h / omega; };
  auto intervals_for = [&](double omega) { return static_cast<long long>(std::ceil(T / h_for(omega) - 1e-9)); };
  const double h_needed = h_for(w1);
  const long long needed = intervals_for(w1);
  const int most = TrajoptOptions{}.max_intervals;
  std::ostringstream os;
  os.precision(4);
  os << "the mesh does not resolve elastic mode" << (first == last ? " " : "s ") << first + 1;
  if (last != first) os << ".." << last + 1;
  os << " of the problem (omega = " << w0;
  if (last != first) os << " .. " << w1;
  os << " rad/s, omega h = " << w0 * h;
  if (last != first) os << " .. " << w1 * h;
  os << " > " << TrajoptResult::max_resolved_omega_h << " with h = " << h
     << " s): the collocation's version of such a mode oscillates at the wrong frequency, so the optimizer's terminal "
        "vibration energy ("
     << r.terminal_vibration_energy_J
     << " J) does not describe that mode's true motion; a [simulation] of the full model measures the residual "
        "vibration; ";
  const bool finer = needed <= most;
  if (first > 0)
    os << "hold only the resolved modes (elastic_modes = " << first << ", modes_at_rest at most " << first << ")"
       << (finer ? " or " : "");
  if (finer)
    os << "use a uniform mesh of at least " << needed << " intervals (h <= " << h_needed << " s)";
  else if (first == 0) {
    const double h1 = h_for(w0);
    const long long needed1 = intervals_for(w0);
    if (needed1 <= most)
      os << "hold fewer modes (elastic_modes = 1 needs a uniform mesh of at least " << needed1 << " intervals, h <= "
         << h1 << " s)";
    else
      os << "no mesh within " << most << " intervals resolves mode 1 (h <= " << h1
         << " s): leave the elastic part out";
  }
  return os.str();
}

}  // namespace freeflex
