// Closed-loop simulations of a TV-LQR law with saturation: on the first-order model it
// was designed on and on the full nonlinear model.
#include "freeflex/control/closed_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "control/gauss_closed_loop.hpp"
#include "freeflex/dynamics/full_model.hpp"
#include "model/commands.hpp"
#include "sim/range_check.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string fmt(double v) { return util::format_number(v, 10); }

/// The control law with saturation, shared by both simulations.
struct Law {
  const TvlqrResult* law = nullptr;
  ActuatorCommandFunction u0;
  Eigen::VectorXd limits;  // empty: none
  int m = 0;

  /// Applied (saturated) and demanded totals u0 + u1 for perturbation x1 at `at`; u0 out.
  void evaluate(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1, Eigen::VectorXd& u0v,
                Eigen::VectorXd& demanded, Eigen::VectorXd& applied) const {
    u0v.setZero(m);
    if (u0) u0(at, u0v);
    demanded = u0v + law->control(at.t, x1);
    applied = demanded;
    if (limits.size())
      for (int k = 0; k < m; ++k) applied(k) = std::clamp(applied(k), -limits(k), limits(k));
  }
};

struct Window {
  double a = 0.0, b = 0.0;
  std::vector<double> outputs;
};

/// The first problem of `o` that does not depend on the model, or "".
std::string options_problem(const ClosedLoopOptions& o) {
  if (!std::isfinite(o.t_begin) || !std::isfinite(o.t_end)) return "t_begin and t_end must be finite";
  if (!(o.output_step_s > 0.0) || !std::isfinite(o.output_step_s))
    return "output_step_s = " + fmt(o.output_step_s) + ", must be finite and > 0";
  for (int k = 0; k < o.limits.size(); ++k)
    if (!(o.limits(k) > 0.0)) return "limits(" + std::to_string(k) + ") = " + fmt(o.limits(k)) + ", must be > 0";
  if (!o.x1_initial.allFinite()) return "x1_initial has a non-finite entry";
  for (double b : o.breakpoints)
    if (!std::isfinite(b)) return "breakpoints must be finite";
  if (o.gauss_steps < 1 || o.gauss_steps > 1000)
    return "gauss_steps = " + std::to_string(o.gauss_steps) + ", expected an integer in [1, 1000]";
  try {
    validate(o.integrator);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

Window window(const TvlqrResult& law, const ClosedLoopOptions& o, const std::string& where) {
  Window w;
  if (o.t_end > o.t_begin) {
    w.a = o.t_begin;
    w.b = o.t_end;
  } else {
    w.a = law.t.front();
    w.b = law.t.back();
  }
  if (!std::isfinite(w.a) || !std::isfinite(w.b))
    throw std::invalid_argument(where + ": t_begin and t_end must be finite");
  if (!(o.output_step_s > 0.0) || !std::isfinite(o.output_step_s))
    throw std::invalid_argument(where + ": output_step_s = " + fmt(o.output_step_s) + ", must be finite and > 0");
  const long steps = std::lround(std::ceil((w.b - w.a) / o.output_step_s - 1e-9));
  for (long i = 0; i < steps; ++i) w.outputs.push_back(w.a + i * o.output_step_s);
  w.outputs.push_back(w.b);
  return w;
}

Law make_law(const FirstOrderModel& model, const TvlqrResult& law, const ActuatorCommandFunction& u0,
             const ClosedLoopOptions& o, const std::string& where) {
  if (!law.ok() || law.K.empty())
    throw std::invalid_argument(where + ": the TV-LQR law was not solved (status message: '" + law.message + "')");
  const int m = model.input_size(), nx = model.state_size();
  if (law.K.front().rows() != m || law.K.front().cols() != nx)
    throw std::invalid_argument(where + ": the law's gains are " + std::to_string(law.K.front().rows()) + " x " +
                                std::to_string(law.K.front().cols()) + ", the model needs " + std::to_string(m) +
                                " x " + std::to_string(nx));
  if (o.limits.size() != 0 && o.limits.size() != m)
    throw std::invalid_argument(where + ": expected " + std::to_string(m) + " actuator limits (or none), got " +
                                std::to_string(o.limits.size()));
  const std::string problem = options_problem(o);
  if (!problem.empty()) throw std::invalid_argument(where + ": " + problem);
  if (o.x1_initial.size() != 0 && o.x1_initial.size() != nx)
    throw std::invalid_argument(where + ": expected x1_initial of size " + std::to_string(nx) + " (or empty), got " +
                                std::to_string(o.x1_initial.size()));
  Law L;
  L.law = &law;
  L.u0 = u0;
  L.limits = o.limits;
  L.m = m;
  return L;
}

std::vector<double> cuts_within(std::vector<double> b, double a, double e) {
  std::vector<double> out;
  for (double x : b)
    if (x > a && x < e) out.push_back(x);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// The integration's status and times, with room for the m commands at each output.
ClosedLoopResult start_result(const IntegrationResult& ir, int m) {
  ClosedLoopResult r;
  r.status = ir.status;
  r.message = ir.ok() ? "" : ir.message;
  r.t = ir.t;
  r.commands.resize(ir.t.size(), m);
  r.demanded.resize(ir.t.size(), m);
  return r;
}

/// Saturation statistics of the filled-in commands, the integrator's counters, wall time.
void finish_result(ClosedLoopResult& r, const IntegrationResult& ir, const Eigen::VectorXd& limits,
                   std::chrono::steady_clock::time_point clock0) {
  r.rhs_evaluations = ir.rhs_evaluations;
  r.steps = ir.steps;
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
  const int T = static_cast<int>(r.commands.rows()), m = static_cast<int>(r.commands.cols());
  r.saturated_fraction_per_actuator = Eigen::VectorXd::Zero(m);
  r.peak_command = T ? r.commands.cwiseAbs().maxCoeff() : 0.0;
  r.peak_demand = T ? r.demanded.cwiseAbs().maxCoeff() : 0.0;
  if (!limits.size() || T == 0) return;
  int any = 0;
  for (int i = 0; i < T; ++i) {
    bool sat = false;
    for (int k = 0; k < m; ++k)
      if (std::abs(r.demanded(i, k)) > limits(k)) {
        r.saturated_fraction_per_actuator(k) += 1.0;
        sat = true;
      }
    any += sat;
  }
  r.saturated_fraction = static_cast<double>(any) / T;
  r.saturated_fraction_per_actuator /= T;
}

}  // namespace

void validate(const ClosedLoopOptions& options) {
  const std::string problem = options_problem(options);
  if (!problem.empty()) throw std::invalid_argument("closed-loop options: " + problem);
}

CommandFunction nominal_element_commands(const Excitation& loads, const std::vector<int>& inputs,
                                         ActuatorCommandFunction u0) {
  const int ne = static_cast<int>(loads.profiles.size());
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const int e = inputs[k];
    if (e < 0 || e >= ne)
      throw std::invalid_argument("nominal_element_commands: actuator " + std::to_string(k) + " is element " +
                                  std::to_string(e) + ", not an element of the excitation (0.." +
                                  std::to_string(ne - 1) + ")");
    if (loads.profiles[e])
      throw std::invalid_argument("nominal_element_commands: element " + std::to_string(e) +
                                  " is an actuator and must not have a load profile");
  }
  return [loads, inputs, u0](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) {
    detail::evaluate_commands(loads, at, c);
    if (!u0) return;
    Eigen::VectorXd u(inputs.size());
    u.setZero();
    u0(at, u);
    for (std::size_t k = 0; k < inputs.size(); ++k) c(inputs[k]) += u(static_cast<Eigen::Index>(k));
  };
}

ClosedLoopResult simulate_closed_loop_first_order(const FirstOrderModel& model, const TvlqrResult& law,
                                                  const ActuatorCommandFunction& u0,
                                                  const ClosedLoopOptions& o) {
  const std::string where = "closed loop (first-order)";
  const Law L = make_law(model, law, u0, o, where);
  const Window w = window(law, o, where);
  const auto clock0 = std::chrono::steady_clock::now();
  const int N = model.body().dofs(), nx = 2 * N, m = L.m;
  const RigidTrajectory& nom = model.nominal();

  FirstOrderModel::Data data = model.create_data();
  OdeSystem sys;
  sys.dim = nx;
  sys.rhs = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1, Eigen::Ref<Eigen::VectorXd> xd) {
    Eigen::VectorXd u0v, dem, app;
    L.evaluate(at, x1, u0v, dem, app);
    xd = model.rhs(data, at, x1, app - u0v);
    return xd.allFinite();
  };
  sys.jacobian = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1, Eigen::Ref<Eigen::MatrixXd> J) {
    const StateSpace& ss = model.state_space(data, at);
    const Eigen::MatrixXd &A = ss.A, &B = ss.B;
    Eigen::VectorXd u0v, dem, app;
    L.evaluate(at, x1, u0v, dem, app);
    Eigen::MatrixXd K = law.gain(at.t);
    for (int k = 0; k < m; ++k)
      if (app(k) != dem(k)) K.row(k).setZero();  // saturated: no feedback through it
    J = A - B * K;
    return J.allFinite();
  };
  sys.last_error = [] { return std::string("the closed-loop first-order right-hand side is not finite"); };
  std::vector<double> bp = nom.breakpoints();
  bp.insert(bp.end(), o.breakpoints.begin(), o.breakpoints.end());
  const Eigen::VectorXd x0 = o.x1_initial.size() ? o.x1_initial : Eigen::VectorXd::Zero(nx);
  IntegrationResult ir;
  if (o.first_order_method == ClosedLoopMethod::Gauss) {
    // the same equations as linear ones, x1' = M x1 + f for each saturation pattern
    detail::SaturatedLinearSystem ls;
    ls.dim = nx;
    ls.inputs = m;
    ls.matrices = [&](const Instant& at, const Eigen::VectorXi& p, Eigen::MatrixXd& M, Eigen::VectorXd& f) {
      const StateSpace& ss = model.state_space(data, at);
      Eigen::VectorXd u0v = Eigen::VectorXd::Zero(m);
      if (L.u0) L.u0(at, u0v);
      Eigen::MatrixXd K = law.gain(at.t);
      Eigen::VectorXd c = law.feedforward_at(at.t);  // u1 at x1 = 0
      for (int k = 0; k < m; ++k)
        if (p(k) != 0) {  // held at its limit: u1 = ±limit − u0, no feedback through it
          K.row(k).setZero();
          c(k) = p(k) * L.limits(k) - u0v(k);
        }
      M = ss.A;
      M.noalias() -= ss.B * K;
      f = ss.g;
      f.noalias() += ss.B * c;
      return M.allFinite() && f.allFinite();
    };
    ls.pattern = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1, Eigen::VectorXi& p) {
      p.setZero(m);
      if (!L.limits.size()) return;
      Eigen::VectorXd u0v, dem, app;
      L.evaluate(at, x1, u0v, dem, app);
      for (int k = 0; k < m; ++k) p(k) = dem(k) > L.limits(k) ? 1 : dem(k) < -L.limits(k) ? -1 : 0;
    };
    detail::GaussOptions go;
    go.steps = o.gauss_steps;
    go.max_total_steps = o.integrator.max_total_steps;
    go.budget = o.integrator.budget;
    go.progress = o.integrator.progress;
    ir = detail::integrate_gauss(ls, x0, w.outputs, cuts_within(bp, w.a, w.b), law.t, go);
  } else {
    ir = integrate(sys, x0, w.outputs, cuts_within(bp, w.a, w.b), o.integrator);
  }

  ClosedLoopResult r = start_result(ir, m);
  const int T = static_cast<int>(ir.t.size());
  r.z.resize(T, N);
  r.z_dot.resize(T, N);
  for (int i = 0; i < T; ++i) {
    const Instant at = Instant::at(ir.t(i));
    const RigidState s = nom.at(at);
    const Eigen::VectorXd x1 = ir.x.row(i).transpose();
    r.z.row(i) = x1.head(N).transpose();
    r.z_dot.row(i) = x1.tail(N).transpose();
    r.z.row(i).head<3>() += s.pos.transpose();
    r.z_dot.row(i).head<3>() += s.vel.transpose();
    Eigen::VectorXd u0v, dem, app;
    L.evaluate(at, x1, u0v, dem, app);
    r.commands.row(i) = app.transpose();
    r.demanded.row(i) = dem.transpose();
  }
  finish_result(r, ir, o.limits, clock0);
  return r;
}

ClosedLoopResult simulate_closed_loop_full(const FirstOrderModel& model, const Excitation& loads,
                                           const ActuatorCommandFunction& u0, const TvlqrResult& law,
                                           const ClosedLoopOptions& o) {
  const std::string where = "closed loop (full model)";
  const Law L = make_law(model, law, u0, o, where);
  const Window w = window(law, o, where);
  const FlexibleBody& body = model.body();
  const int ne = static_cast<int>(body.elements().size());
  if (static_cast<int>(loads.profiles.size()) != ne)
    throw std::invalid_argument(where + ": expected a load profile slot for each of the " + std::to_string(ne) +
                                " elements, got " + std::to_string(loads.profiles.size()));
  for (int e : model.inputs())
    if (loads.profiles[e])
      throw std::invalid_argument(where + ": element " + std::to_string(e) + " ('" + body.elements()[e].name +
                                  "') is an actuator and must not have a load profile");
  const auto clock0 = std::chrono::steady_clock::now();
  const int N = body.dofs(), nx = 2 * N, m = L.m;
  const RigidTrajectory& nom = model.nominal();
  const FullModel full(body);
  auto data = std::make_shared<FullModel::Data>(full.create_data());

  auto perturbation = [&nom, N](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x) {
    const RigidState s = nom.at(at);
    Eigen::VectorXd x1 = x;
    x1.head<3>() -= s.pos;
    x1.segment<3>(N) -= s.vel;
    return x1;
  };
  auto commands = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::VectorXd& c,
                      Eigen::VectorXd& dem, Eigen::VectorXd& app) {
    c.resize(ne);
    detail::evaluate_commands(loads, at, c);
    Eigen::VectorXd u0v;
    L.evaluate(at, perturbation(at, x), u0v, dem, app);
    for (int k = 0; k < m; ++k) c(model.inputs()[k]) += app(k);
  };
  OdeSystem sys;
  sys.dim = nx;
  sys.rhs = [&](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> xd) {
    Eigen::VectorXd c, dem, app;
    commands(at, x, c, dem, app);
    if (!full.rhs(*data, x, c)) return false;
    xd = data->x_dot;
    return true;
  };
  sys.last_error = detail::mass_matrix_failure(body);

  std::vector<double> bp = nom.breakpoints();
  const std::vector<double> lb = loads.breakpoints();
  bp.insert(bp.end(), lb.begin(), lb.end());
  bp.insert(bp.end(), o.breakpoints.begin(), o.breakpoints.end());
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(nx);
  {
    const RigidState s0 = nom.at(Instant::at(w.a));
    x0.head<3>() = s0.pos;
    x0.segment<3>(N) = s0.vel;
    if (o.x1_initial.size()) x0 += o.x1_initial;
  }
  const IntegrationResult ir = integrate(sys, x0, w.outputs, cuts_within(bp, w.a, w.b), o.integrator);

  ClosedLoopResult r = start_result(ir, m);
  const int T = static_cast<int>(ir.t.size());
  r.z = ir.x.leftCols(N);
  r.z_dot = ir.x.rightCols(N);
  for (int i = 0; i < T; ++i) {
    Eigen::VectorXd c, dem, app;
    commands(Instant::at(ir.t(i)), ir.x.row(i).transpose(), c, dem, app);
    r.commands.row(i) = app.transpose();
    r.demanded.row(i) = dem.transpose();
  }
  finish_result(r, ir, o.limits, clock0);
  return r;
}

}  // namespace freeflex
