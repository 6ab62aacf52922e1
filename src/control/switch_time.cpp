// Bang-bang switch-time design (see the header for the formulation): the closed-form
// roots by a continuation in the number of modes, the shortest of them carried into the
// first-order model, the work bound, and the options.
#include "freeflex/control/switch_time.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>

#include "control/switch_time_model.hpp"
#include "control/switch_time_stages.hpp"

namespace freeflex {
namespace {

using namespace detail;
std::string fmt(double v) { return fmt10(v); }

/// Largest step limits accepted (a simulation at that many steps takes days).
constexpr long kMaxSteps = 1000000000000L;
/// Closed-form roots for k' − 1 modes that start the runs for k' (the shortest ones).
constexpr int kParents = 3;
/// Offsets of an inserted switch: the new mode's half period π/ω times 1, 1/2, ... 1/16.
constexpr int kSpreads = 5;
static_assert(kParents * kSpreads == 15, "switch_time_work counts 15 runs per insertion point");
/// Closed-form roots this much longer than the shortest first-order root found are not
/// carried over: the first-order roots lie within 0.45% of their closed-form roots (measured).
constexpr double kCarryMargin = 0.01;

/// Random antisymmetric starts: half-durations in [0.5, 0.8] T*, k switches in each half.
std::vector<std::vector<double>> random_starts(int k, double Tstar, int count) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<std::vector<double>> starts;
  for (int s = 0; s < count; ++s) {
    const double h = 0.5 * Tstar * (1.0 + 0.6 * U(rng));
    std::vector<double> sw(k);
    for (double& v : sw) v = h * U(rng);
    std::sort(sw.begin(), sw.end());
    std::vector<double> half;  // durations of the first half
    double prev = 0.0;
    for (double v : sw) half.push_back(v - prev), prev = v;
    half.push_back(h - prev);
    std::vector<double> D = half;
    D.insert(D.end(), half.rbegin(), half.rend());
    starts.push_back(D);
  }
  return starts;
}

/// Antisymmetric starts for one mode more than `parent` has: its switches before T/2,
/// with one more inserted `spread` before or after each of them or T/2, mirrored about T/2.
void add_insertions(const std::vector<double>& parent, double spread, std::vector<std::vector<double>>& starts) {
  double T = 0.0;
  const std::vector<double> sw = switches_of(parent, T);
  const std::vector<double> left(sw.begin(), sw.begin() + static_cast<long>(sw.size() / 2));
  std::vector<double> near = left;
  near.push_back(0.5 * T);
  for (double c : near)
    for (double x : {c - spread, c + spread}) {
      if (!(x > 0.0) || !(x < 0.5 * T)) continue;
      std::vector<double> L = left;
      L.insert(std::upper_bound(L.begin(), L.end(), x), x);
      std::vector<double> D;
      double prev = 0.0;
      for (double l : L) D.push_back(l - prev), prev = l;
      D.push_back(0.5 * T - prev);
      for (std::size_t i = L.size() + 1; i-- > 0;) D.push_back(D[i]);
      if (*std::min_element(D.begin(), D.end()) > 0.0) starts.push_back(D);
    }
}

/// Stage 1: the closed-form roots for k modes (distinct, shortest first), by a
/// continuation in the number of modes from the rigid answer: the shortest roots for
/// k' − 1 modes, with a switch inserted near each switch (add_insertions), start the
/// SLSQP runs for k' (each mode more adds a short notch to the near-rigid cluster:
/// theory.md section 12); `random` random antisymmetric starts join at k' = k.
std::vector<StageResult> closed_form_roots(Problem& P, int random, double tol, int max_eval) {
  const double Tstar = 2.0 * P.scale / std::sqrt(P.I_o) / P.a;
  const int k = P.k;
  std::vector<StageResult> roots(1);
  roots[0].D = {0.5 * Tstar, 0.5 * Tstar};  // the rigid answer, k = 0
  roots[0].T = Tstar;
  for (int kk = 1; kk <= k; ++kk) {
    P.k = kk;  // the constraints of the first kk modes
    std::vector<std::vector<double>> starts;
    for (std::size_t p = 0; p < roots.size() && p < static_cast<std::size_t>(kParents); ++p)
      for (int i = 0; i < kSpreads; ++i) add_insertions(roots[p].D, M_PI / P.modes.omega(kk - 1) / (1 << i), starts);
    if (kk == k)
      for (auto& D : random_starts(k, Tstar, random)) starts.push_back(std::move(D));
    std::vector<StageResult> found;
    for (const std::vector<double>& D : starts) {
      const StageResult r = run_slsqp(P, true, D, tol, max_eval);
      if (!r.feasible) continue;
      bool seen = false;
      for (const auto& q : found) {
        double dist = 0.0;
        for (std::size_t i = 0; i < q.D.size(); ++i) dist = std::max(dist, std::abs(q.D[i] - r.D[i]));
        seen = seen || dist < 1e-6 * Tstar;
      }
      if (!seen) found.push_back(r);
    }
    std::sort(found.begin(), found.end(), [](const StageResult& a, const StageResult& b) { return a.T < b.T; });
    roots = std::move(found);
    if (roots.empty()) kk = std::max(kk, k - 1);  // nothing to continue: the random starts at k alone
  }
  P.k = k;
  return roots;
}

/// The first problem of `o`, naming the setting, or "".
std::string options_problem(const SwitchTimeOptions& o) {
  auto positive = [](const char* name, double v) {
    return v > 0.0 && std::isfinite(v) ? std::string()
                                        : std::string(name) + " = " + fmt(v) + ", must be finite and > 0";
  };
  auto in = [](const char* name, long v, long lo, long hi) {
    return v >= lo && v <= hi ? std::string()
                              : std::string(name) + " = " + std::to_string(v) + ", must be in [" + std::to_string(lo) +
                                    ", " + std::to_string(hi) + "]";
  };
  for (const std::string& p :
       {positive("rtol", o.rtol), positive("atol", o.atol), positive("constraint_tolerance", o.constraint_tolerance),
        in("max_steps_per_simulation", o.max_steps_per_simulation, 0, kMaxSteps),
        in("max_total_steps", o.max_total_steps, 0, kMaxSteps), in("starts", o.starts, 1, 10000),
        in("max_evaluations", o.max_evaluations, 1, 100000), in("refine_roots", o.refine_roots, 1, 100),
        in("simulations_per_unknown", o.simulations_per_unknown, 1, 10000)})
    if (!p.empty()) return p;
  return "";
}

}  // namespace

void validate(const SwitchTimeOptions& o) {
  const std::string problem = options_problem(o);
  if (!problem.empty()) throw std::invalid_argument("switch-time options: " + problem);
}

SwitchTimeWork switch_time_work(int modes, const SwitchTimeOptions& o) {
  if (modes < 0 || modes > 4)
    throw std::invalid_argument("switch_time_work: modes = " + std::to_string(modes) + ", must be in [0, 4]");
  validate(o);
  const long k = modes;
  SwitchTimeWork w;
  // continuation runs: at most 10 at k' = 1, then kParents x kSpreads x 2k' insertions
  // (15k² + 15k − 20 in all, at most 30 k²), and the random starts; one check each
  w.closed_form_evaluations = (o.starts + 30 * k * k) * (o.max_evaluations + 1L);
  w.simulations = k == 0 ? 1 : static_cast<long>(o.refine_roots) * o.simulations_per_unknown * (2 * k + 2) + 2;
  const long by_each = o.max_steps_per_simulation > 0 ? w.simulations * o.max_steps_per_simulation : 0;
  w.steps = o.max_total_steps > 0 && (by_each == 0 || o.max_total_steps < by_each) ? o.max_total_steps : by_each;
  return w;
}

SwitchTimeResult design_switch_times(const FlexibleBody& body, int actuator, double rotation_rad,
                                     double torque_limit_Nm, int modes, const SwitchTimeOptions& o) {
  const std::string where = "design_switch_times";
  validate_actuator(body, actuator, where);
  if (!(rotation_rad > 0.0) || !std::isfinite(rotation_rad))
    throw std::invalid_argument(where + ": rotation_rad = " + fmt(rotation_rad) + ", must be finite and > 0");
  if (!(torque_limit_Nm > 0.0) || !std::isfinite(torque_limit_Nm))
    throw std::invalid_argument(where + ": torque_limit_Nm = " + fmt(torque_limit_Nm) + ", must be finite and > 0");
  if (modes < 0 || modes > 4)
    throw std::invalid_argument(where + ": modes = " + std::to_string(modes) + ", must be in [0, 4]");
  const std::string problem = options_problem(o);
  if (!problem.empty()) throw std::invalid_argument(where + ": " + problem);
  const auto clock0 = std::chrono::steady_clock::now();

  Problem P;
  P.body = &body;
  P.actuator = actuator;
  P.k = modes;
  P.I_o = body.integrals().I_o;
  P.tau = torque_limit_Nm;
  P.a = P.tau / P.I_o;
  P.dtheta = rotation_rad;
  P.rtol = o.rtol;
  P.atol = o.atol;
  P.max_total_steps = o.max_steps_per_simulation;
  P.budget = o.budget;
  P.progress = o.progress;
  P.modes = target_modes(body, actuator, rotation_rad, modes, where);
  const double Tstar = 2.0 * std::sqrt(P.I_o * P.dtheta / P.tau);
  P.scale = std::sqrt(P.I_o) * P.a * Tstar / 2.0;  // sqrt(I_o) θ'* (rigid peak rate)

  SwitchTimeResult res;
  res.rigid_duration_s = Tstar;
  res.torque_limit_Nm = P.tau;
  res.mode_frequencies_rad_s = P.modes.omega;

  // Stage 1: the closed form, continued in k from the rigid answer.
  const std::vector<StageResult> roots =
      P.k == 0 ? std::vector<StageResult>{run_slsqp(P, true, {0.5 * Tstar, 0.5 * Tstar}, o.constraint_tolerance,
                                                    o.max_evaluations)}
               : closed_form_roots(P, o.starts, o.constraint_tolerance, o.max_evaluations);
  res.closed_form_roots = static_cast<int>(roots.size());
  auto done = [&]() {  // the work done, on every return
    res.closed_form_evaluations = P.closed_form_evaluations;
    res.simulations = P.simulations;
    res.steps = P.steps;
    res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return res;
  };
  if (roots.empty() || !roots.front().feasible) {
    res.message = "closed-form stage found no feasible switch times (" + std::to_string(o.starts) +
                  " random starts besides the continuation from the rigid answer)";
    return done();
  }

  // Stage 2: the shortest closed-form roots carried into the first-order model, each
  // within its simulation budget; the shortest first-order root kept.
  StageResult best = roots.front(), fin = best;
  fin.feasible = P.k == 0;  // the closed form is the rigid problem itself
  std::string stage2_error;
  int carried = 0;
  const int per_root = o.simulations_per_unknown * (2 * P.k + 2);
  for (std::size_t i = 0; P.k > 0 && i < roots.size() && i < static_cast<std::size_t>(o.refine_roots); ++i) {
    if (fin.feasible && roots[i].T > (1.0 + kCarryMargin) * fin.T) break;
    // with a design in hand, keep steps for the two checks at the end (each about as long
    // as the longest simulation so far)
    const long cap = o.max_total_steps - (fin.feasible ? 2 * P.longest : 0);
    if (o.max_total_steps > 0 && cap <= P.steps) break;
    P.max_steps_all = o.max_total_steps > 0 ? cap : 0;
    P.max_simulations = P.simulations + per_root;
    P.budget_spent = false;
    ++carried;
    const StageResult r = continue_to_first_order(P, roots[i].D, o.constraint_tolerance,
                                                  o.refine == SwitchTimeOptions::Refine::Slsqp, o.max_evaluations);
    if (r.feasible && (!fin.feasible || r.T < fin.T)) best = roots[i], fin = r;
    if (!fin.feasible) fin = r, best = roots[i], stage2_error = P.last_error;
  }
  // the two checks below: within the design's step budget, outside the roots'
  P.max_simulations = P.simulations + 2;
  P.max_steps_all = o.max_total_steps;
  P.budget_spent = false;
  res.closed_form_switch_times = switches_of(best.D, res.closed_form_duration_s);
  if (P.k > 0) {
    Eigen::VectorXd x1c;
    if (simulate(P, best.D, x1c)) {
      std::vector<double> cc(2 * P.k);
      modal_from_state(P, x1c, cc.data());
      double e = 0.0;
      for (double v : cc) e += v * v;  // Σ E_j / E*, E* = ½ I_o θ'*² (the closed form's peak rate)
      res.closed_form_residual_ratio = e;
    }
  }
  res.switch_times = switches_of(fin.D, res.duration_s);
  Eigen::VectorXd x1;
  double peak = 0.0;
  const std::string stage2 = "none of the " + std::to_string(carried) + " shortest of " + std::to_string(roots.size()) +
                             " closed-form roots carried into the first-order model; the last: max violation " +
                             fmt(fin.violation) + (stage2_error.empty() ? "" : " (" + stage2_error + ")");
  if (!simulate(P, fin.D, x1, &peak)) {
    res.message = fin.feasible ? "first-order simulation of the design failed: " + P.last_error : stage2;
    return done();
  }
  rigid_end(fin.D, P.a, res.final_angle_rad, res.final_rate_rad_s, nullptr, nullptr);
  const int N = body.dofs();
  const Eigen::VectorXd eta = P.modes.shapes.transpose() * (P.modes.M0 * x1.head(N));
  const Eigen::VectorXd eta_d = P.modes.shapes.transpose() * (P.modes.M0 * x1.tail(N));
  res.residual_energy_J = 0.5 * (eta_d.cwiseAbs2() + P.modes.omega.cwiseAbs2().cwiseProduct(eta.cwiseAbs2()));
  res.peak_rate_rad_s = peak;
  res.rigid_kinetic_peak_J = 0.5 * P.I_o * peak * peak;
  res.residual_ratio = res.residual_energy_J.sum() / res.rigid_kinetic_peak_J;
  res.status = fin.feasible ? SwitchTimeResult::Status::Solved : SwitchTimeResult::Status::NotConverged;
  res.message = fin.feasible ? "solved" : stage2;
  return done();
}

}  // namespace freeflex
