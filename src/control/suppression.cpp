// Vibration suppression in one call (control/suppression.hpp): nominal motion, open loop,
// first-order model, TV-LQR and the closed loops, in that order.
#include "freeflex/control/suppression.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "freeflex/control/lqr.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string num(double v) { return util::format_number(v, 10); }

void check_problem(const FlexibleBody& body, const SuppressionProblem& p) {
  const std::string where = "suppress_vibration";
  auto fail = [&](const std::string& what) { throw std::invalid_argument(where + ": " + what); };
  const int ne = static_cast<int>(body.elements().size()), m = static_cast<int>(p.actuators.size());
  if (static_cast<int>(p.loads.profiles.size()) != ne)
    fail("expected a load profile slot for each of the " + std::to_string(ne) + " elements, got " +
         std::to_string(p.loads.profiles.size()));
  if (m < 1) fail("expected at least one feedback actuator, got none");
  for (int e : p.actuators)
    if (e < 0 || e >= ne) fail("actuator " + std::to_string(e) + " is not an element of the body (0.." + std::to_string(ne - 1) + ")");
  if (p.limits.size() != m)
    fail("expected one limit per feedback actuator (" + std::to_string(m) + "), got " + std::to_string(p.limits.size()));
  if (!(p.horizon_s > 0.0) || !std::isfinite(p.horizon_s)) fail("horizon_s = " + num(p.horizon_s) + ", must be finite and > 0");
  if (!(p.until_s > 0.0) || !std::isfinite(p.until_s)) fail("until_s = " + num(p.until_s) + ", must be finite and > 0");
  check_positive_semidefinite(p.Q, 2 * body.dofs(), "Q", where);
  check_positive_definite(p.R, m, "R", where);
  if (p.maneuver) {
    if (!p.maneuver->motion || !p.maneuver->commands) fail("the maneuver needs a motion and commands");
    for (int a : p.maneuver->actuators)
      if (std::find(p.actuators.begin(), p.actuators.end(), a) == p.actuators.end())
        fail("the feedback actuators must include every maneuver actuator; element " + std::to_string(a) + " is missing");
  }
}

}  // namespace

ActuatorCommandFunction maneuver_actuator_commands(const FlownManeuver& m, const std::vector<int>& actuators) {
  std::vector<int> slot;  // position of each maneuver actuator among the feedback ones
  for (int a : m.actuators)
    slot.push_back(static_cast<int>(std::find(actuators.begin(), actuators.end(), a) - actuators.begin()));
  const auto commands = m.commands;
  const double end = m.duration_s;
  return [commands, slot, end](const Instant& at, Eigen::Ref<Eigen::VectorXd> u) {
    u.setZero();
    if (at.piece_mid > end) return;
    Eigen::VectorXd c(static_cast<Eigen::Index>(slot.size()));
    commands(at, c);
    for (std::size_t k = 0; k < slot.size(); ++k) u(slot[k]) = c(static_cast<Eigen::Index>(k));
  };
}

void validate(const SuppressionOptions& o) {
  SimulationOptions sim = o.simulation;
  sim.duration_s = std::max(sim.duration_s, sim.output_step_s);  // the chain sets the duration itself
  validate(sim);
  validate(o.tvlqr);
  validate(o.closed_loop);
  ClosedLoopOptions co;
  co.first_order_method = o.closed_loop_first_order_method;
  co.gauss_steps = o.closed_loop_gauss_steps;
  validate(co);
}

SuppressionResult suppress_vibration(const FlexibleBody& body, const SuppressionProblem& p,
                                     const SuppressionOptions& o) {
  validate(o);
  check_problem(body, p);
  SuppressionResult res;
  auto phase = [&](SuppressionPhase ph, bool done, double total) {
    if (o.on_phase) o.on_phase(ph, done, total, res);
  };
  auto progress = [&](SuppressionPhase ph, double covered) {
    if (o.progress) o.progress(ph, covered);
  };
  SimulationOptions sim = o.simulation;
  sim.duration_s = p.until_s;

  // 1. The nominal motion and the nominal commands u0 of the feedback actuators.
  Excitation nominal_ex = p.loads;
  std::shared_ptr<const RigidTrajectory> nominal;
  ActuatorCommandFunction u0;
  if (p.maneuver) {
    const FlownManeuver& m = *p.maneuver;
    u0 = maneuver_actuator_commands(m, p.actuators);
    nominal_ex = m.driving(p.loads);
    nominal = m.nominal();
    if (m.duration_s > p.horizon_s) {
      res.status = SuppressionResult::Status::HorizonTooShort;
      res.message = "horizon_s = " + num(p.horizon_s) + " is shorter than the maneuver (" + num(m.duration_s) +
                    " s): no feedback was designed";
      return res;
    }
  }

  // 2. Open loop: the perturbation solution, then the full model.
  phase(SuppressionPhase::OpenLoop, false, 2.0 * sim.duration_s);  // the two runs, one after the other
  SimulationOptions sim_p = with_reusable_nominal(sim);  // its nominal serves the TV-LQR design
  sim_p.integrator.progress = [&](double t) { progress(SuppressionPhase::OpenLoop, t); };
  res.open_loop_first_order = nominal ? simulate_perturbation_about(body, nominal_ex, nominal, sim_p)
                                      : simulate_perturbation(body, nominal_ex, sim_p);
  if (!res.open_loop_first_order.total.ok()) {
    res.status = SuppressionResult::Status::OpenLoopFailed;
    res.message = "open-loop perturbation simulation failed: " + res.open_loop_first_order.total.message;
    return res;
  }
  if (!nominal) nominal = res.open_loop_first_order.nominal;
  res.nominal = nominal;
  res.u0 = u0 ? u0 : [](const Instant&, Eigen::Ref<Eigen::VectorXd> u) { u.setZero(); };
  sim_p.integrator.progress = [&](double t) { progress(SuppressionPhase::OpenLoop, sim.duration_s + t); };
  res.open_loop_full = simulate_full(body, nominal_ex, sim_p);
  if (!res.open_loop_full.ok()) {
    res.status = SuppressionResult::Status::OpenLoopFailed;
    res.message = "open-loop full simulation failed: " + res.open_loop_full.message;
    return res;
  }
  phase(SuppressionPhase::OpenLoop, true, 2.0 * sim.duration_s);

  // 3. TV-LQR on the first-order model about the nominal motion.
  const FirstOrderModel fo(body, *nominal, nominal_element_commands(p.loads, p.actuators, u0), p.actuators);
  TvlqrOptions to = o.tvlqr;
  for (double b : p.loads.breakpoints()) to.breakpoints.push_back(b);
  to.progress = [&](double covered) { progress(SuppressionPhase::Tvlqr, covered); };  // the backward sweep, tf - t
  phase(SuppressionPhase::Tvlqr, false, p.horizon_s);
  res.law = solve_tvlqr(fo, 0.0, p.horizon_s, p.Q, p.R, to);
  phase(SuppressionPhase::Tvlqr, true, p.horizon_s);
  if (!res.law.ok()) {
    res.status = SuppressionResult::Status::TvlqrFailed;
    res.message = "TV-LQR failed: " + res.law.message;
    return res;
  }

  // 4. The law on the first-order model and on the full model.
  ClosedLoopOptions co;
  co.integrator = o.closed_loop;
  co.first_order_method = o.closed_loop_first_order_method;
  co.gauss_steps = o.closed_loop_gauss_steps;
  co.t_begin = 0.0;
  co.t_end = p.until_s;
  co.output_step_s = sim.output_step_s;
  co.limits = p.limits;
  for (double b : p.loads.breakpoints()) co.breakpoints.push_back(b);
  const double span = co.t_end - co.t_begin;
  phase(SuppressionPhase::ClosedLoop, false, 2.0 * span);  // the two runs, one after the other
  co.integrator.progress = [&](double t) { progress(SuppressionPhase::ClosedLoop, t - co.t_begin); };
  res.closed_loop_first_order = simulate_closed_loop_first_order(fo, res.law, u0, co);
  co.integrator.progress = [&](double t) { progress(SuppressionPhase::ClosedLoop, span + t - co.t_begin); };
  res.closed_loop_full = simulate_closed_loop_full(fo, p.loads, u0, res.law, co);
  phase(SuppressionPhase::ClosedLoop, true, 2.0 * span);
  res.status = SuppressionResult::Status::Solved;
  res.message = "solved";
  for (const ClosedLoopResult* r : {&res.closed_loop_first_order, &res.closed_loop_full})
    if (!r->ok()) {
      res.status = SuppressionResult::Status::ClosedLoopFailed;
      res.message = "closed-loop simulation failed: " + r->message;
    }
  return res;
}

}  // namespace freeflex
