// Validation of maneuver problems and trajectory-optimization options: every problem
// found, each with the field it concerns.
#include "freeflex/trajopt/problem.hpp"
#include "util/format.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace freeflex {

namespace {

std::string num(double v) { return util::format_number(v, 10); }

std::string item(const std::string& name, int k) { return name + "[" + std::to_string(k) + "]"; }

/// Collects problems; each message starts with the field it names.
struct Problems {
  std::vector<FieldProblem> list;
  void push_back(const std::string& field, const std::string& message) { list.push_back({field, message}); }
};

}  // namespace

std::vector<FieldProblem> problems(const ManeuverProblem& p, int ne) {
  Problems err;
  const int nu = static_cast<int>(p.actuators.size());
  if (nu == 0) err.push_back("actuators", "actuators is empty, expected at least one element index");
  for (int k = 0; k < nu; ++k) {
    const int e = p.actuators[k];
    if (e < 0 || e >= ne)
      err.push_back(item("actuators", k), item("actuators", k) + " = " + std::to_string(e) + ", expected an element index in [0, " +
                    std::to_string(ne - 1) + "] (the body has " + std::to_string(ne) + " elements)");
    for (int j = 0; j < k; ++j)
      if (p.actuators[j] == e)
        err.push_back(item("actuators", k), item("actuators", k) + " = " + std::to_string(e) + " repeats " + item("actuators", j) +
                      ", expected distinct elements");
  }
  auto check_size = [&](const Eigen::VectorXd& v, const std::string& name) {
    if (v.size() != nu) {
      err.push_back(name, name + " has " + std::to_string(v.size()) + " entries, expected " + std::to_string(nu) +
                    " (one per actuator)");
      return false;
    }
    return true;
  };
  if (check_size(p.u_min, "u_min") && check_size(p.u_max, "u_max"))
    for (int k = 0; k < nu; ++k)
      if (std::isnan(p.u_min(k)) || std::isnan(p.u_max(k)) || p.u_min(k) > p.u_max(k) || p.u_min(k) == ManeuverProblem::inf ||
          p.u_max(k) == -ManeuverProblem::inf)
        err.push_back(item("u_min", k), item("u_min", k) + " = " + num(p.u_min(k)) + ", " + item("u_max", k) + " = " + num(p.u_max(k)) +
                      ", expected u_min <= u_max");
  if (p.du_max && check_size(*p.du_max, "du_max"))
    for (int k = 0; k < nu; ++k)
      if (!((*p.du_max)(k) > 0.0))
        err.push_back(item("du_max", k), item("du_max", k) + " = " + num((*p.du_max)(k)) + ", expected > 0 (infinity for no bound)");
  if (!p.x_initial.allFinite()) err.push_back("x_initial", "x_initial has a non-finite entry");
  if (!p.x_final.allFinite()) err.push_back("x_final", "x_final has a non-finite entry");
  for (int i = 0; i < 6; ++i)
    if (std::isnan(p.x_min(i)) || std::isnan(p.x_max(i)) || p.x_min(i) > p.x_max(i))
      err.push_back(item("x_min", i), item("x_min", i) + " = " + num(p.x_min(i)) + ", " + item("x_max", i) + " = " + num(p.x_max(i)) +
                    ", expected x_min <= x_max");
  if (!(p.duration_s > 0.0) || !std::isfinite(p.duration_s))
    err.push_back("duration_s", "duration_s = " + num(p.duration_s) + ", expected a finite value > 0");
  if (p.free_time) {
    if (!(p.t_min_s > 0.0) || !std::isfinite(p.t_min_s))
      err.push_back("t_min_s", "t_min_s = " + num(p.t_min_s) + ", expected a finite value > 0");
    if (!(p.t_max_s > 0.0) || !std::isfinite(p.t_max_s))
      err.push_back("t_max_s", "t_max_s = " + num(p.t_max_s) + ", expected a finite value > 0");
    if (p.t_min_s > p.t_max_s)
      err.push_back("t_min_s", "free time with t_min_s = " + num(p.t_min_s) + " > t_max_s = " + num(p.t_max_s) +
                    ", expected t_min_s <= t_max_s");
  }
  const std::pair<const char*, double> weights[] = {
      {"w_energy", p.w_energy}, {"w_time", p.w_time}, {"w_smooth", p.w_smooth}};
  for (const auto& w : weights)
    if (!(w.second >= 0.0) || !std::isfinite(w.second))
      err.push_back(w.first, std::string(w.first) + " = " + num(w.second) + ", expected a finite value >= 0");
  if (!(p.w_vibration >= 0.0) || !std::isfinite(p.w_vibration))
    err.push_back("w_vibration", "w_vibration = " + num(p.w_vibration) + ", expected a finite value >= 0");
  if (!(p.w_energy > 0.0 || p.w_time > 0.0 || p.w_smooth > 0.0 || p.w_vibration > 0.0))
    err.push_back("w_energy", "w_energy, w_time, w_smooth and w_vibration are all 0, expected at least one > 0");
  if (p.modes_at_rest < ManeuverProblem::all_modes)
    err.push_back("modes_at_rest", "modes_at_rest = " + std::to_string(p.modes_at_rest) +
                  ", expected >= 0 or all_modes (-1)");
  if (!(p.tip_deflection_limit_m > 0.0))
    err.push_back("tip_deflection_limit_m", "tip_deflection_limit_m = " + num(p.tip_deflection_limit_m) +
                  ", expected > 0 (infinity for no bound)");
  if (p.zero_end_commands && p.u_min.size() == nu && p.u_max.size() == nu)
    for (int k = 0; k < nu; ++k)
      if (p.u_min(k) > 0.0 || p.u_max(k) < 0.0)
        err.push_back(item("u_min", k), "zero_end_commands needs 0 within [u_min, u_max], got " + item("u_min", k) +
                      " = " + num(p.u_min(k)) + ", " + item("u_max", k) + " = " + num(p.u_max(k)));
  if (p.elastic_modes < ManeuverProblem::all_modes || p.elastic_modes == 0)
    err.push_back("elastic_modes", "elastic_modes = " + std::to_string(p.elastic_modes) +
                  ", expected >= 1 or all_modes (-1)");
  else if (p.elastic_modes > 0 && p.modes_at_rest > p.elastic_modes)
    err.push_back("modes_at_rest", "modes_at_rest = " + std::to_string(p.modes_at_rest) +
                  ", expected at most elastic_modes = " + std::to_string(p.elastic_modes) +
                  " (the modes the problem holds)");
  if (!p.elastic) {
    if (p.elastic_modes != ManeuverProblem::all_modes)
      err.push_back("elastic_modes", "elastic_modes = " + std::to_string(p.elastic_modes) + " needs elastic = true");
    if (p.modes_at_rest != 0)
      err.push_back("modes_at_rest", "modes_at_rest = " + std::to_string(p.modes_at_rest) + " needs elastic = true");
    if (p.w_vibration != 0.0)
      err.push_back("w_vibration", "w_vibration = " + num(p.w_vibration) + " needs elastic = true");
    if (p.tip_deflection_limit_m != ManeuverProblem::inf)
      err.push_back("tip_deflection_limit_m",
                    "tip_deflection_limit_m = " + num(p.tip_deflection_limit_m) + " needs elastic = true");
  }
  if (p.w_time > 0.0 && !p.free_time)
    err.push_back("w_time", "w_time = " + num(p.w_time) + " with a fixed duration, expected free_time = true");
  if (p.energy_weights.size() != 0 && check_size(p.energy_weights, "energy_weights"))
    for (int k = 0; k < nu; ++k)
      if (!(p.energy_weights(k) >= 0.0) || !std::isfinite(p.energy_weights(k)))
        err.push_back(item("energy_weights", k), item("energy_weights", k) + " = " + num(p.energy_weights(k)) + ", expected a finite value >= 0");
  return err.list;
}

std::vector<FieldProblem> problems(const TrajoptOptions& o) {
  Problems err;
  if (o.intervals < 1) err.push_back("intervals", "intervals = " + std::to_string(o.intervals) + ", expected >= 1");
  if (o.mesh_refinements < 0)
    err.push_back("mesh_refinements", "mesh_refinements = " + std::to_string(o.mesh_refinements) + ", expected >= 0");
  if (!(o.mesh_tolerance > 0.0)) err.push_back("mesh_tolerance", "mesh_tolerance = " + num(o.mesh_tolerance) + ", expected > 0");
  if (o.max_intervals < o.intervals)
    err.push_back("max_intervals", "max_intervals = " + std::to_string(o.max_intervals) + ", expected >= intervals = " +
                  std::to_string(o.intervals));
  if (!(o.tol > 0.0)) err.push_back("tol", "tol = " + num(o.tol) + ", expected > 0");
  if (o.max_iter < 0) err.push_back("max_iter", "max_iter = " + std::to_string(o.max_iter) + ", expected >= 0");
  if (o.derivative_test != "none" && o.derivative_test != "first-order" && o.derivative_test != "second-order" &&
      o.derivative_test != "only-second-order")
    err.push_back("derivative_test", "derivative_test = '" + o.derivative_test +
                  "', expected none, first-order, second-order or only-second-order");
  for (std::size_t i = 0; i < o.ipopt_options.size(); ++i)
    if (o.ipopt_options[i].first.empty())
      err.push_back("ipopt_options[" + std::to_string(i) + "]", "ipopt_options[" + std::to_string(i) + "] has an empty name");
  if (o.guess.rollout && !o.guess.control) err.push_back("guess.rollout", "guess.rollout = true needs guess.control");
  return err.list;
}

void validate(const FlexibleBody& body, const ManeuverProblem& problem) {
  std::vector<FieldProblem> list = problems(problem, static_cast<int>(body.elements().size()));
  if (problem.elastic && problem.elastic_modes > body.n())
    list.push_back({"elastic_modes", "elastic_modes = " + std::to_string(problem.elastic_modes) +
                                         ", expected at most the " + std::to_string(body.n()) +
                                         " elastic coordinates of the body"});
  if (problem.elastic && problem.modes_at_rest > body.n())
    list.push_back({"modes_at_rest", "modes_at_rest = " + std::to_string(problem.modes_at_rest) +
                                         ", expected at most the " + std::to_string(body.n()) +
                                         " elastic coordinates of the body"});
  throw_if_any("maneuver problem", list);
}

void validate(const TrajoptOptions& options) { throw_if_any("trajopt options", problems(options)); }

ManeuverProblem rigid_counterpart(const ManeuverProblem& problem) {
  ManeuverProblem p = problem;
  p.elastic = false;
  p.elastic_modes = ManeuverProblem::all_modes;
  p.modes_at_rest = 0;
  p.w_vibration = 0.0;
  p.tip_deflection_limit_m = ManeuverProblem::inf;
  return p;
}

}  // namespace freeflex
