// Simulations of the three models: the full model, and the perturbation solution
// (zero-order motion, then the first-order model about it).
#include "freeflex/sim/simulate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "dynamics/body_kernels.hpp"
#include "dynamics/rest_mode_model.hpp"
#include "model/commands.hpp"
#include "util/format.hpp"
#include "sim/ltv_taylor.hpp"
#include "sim/modal_variables.hpp"
#include "sim/range_check.hpp"
#include "util/finite.hpp"

namespace freeflex {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }


/// The loads' breakpoints inside (0, t_end), ascending; one that leaves a piece integrate()
/// would not step over (roundoff_span: from 0, from the one before it, or up to t_end) is left
/// out, so that every piece has a length to divide by (the zero-order trajectory's samples).
std::vector<double> breakpoints_within(const Excitation& ex, double t_end) {
  std::vector<double> all = ex.breakpoints(), b;
  std::sort(all.begin(), all.end());
  double last = 0.0;
  for (double t : all)
    if (t > last && !roundoff_span(last, t) && !roundoff_span(t, t_end)) b.push_back(last = t);
  return b;
}

/// The nominal motion as the first-order simulation asks for it: its model and its modal
/// variables both need the state at the time of each right-hand side call, so the last
/// one is kept (one simulation, one thread).
class LastStateCache : public RigidTrajectory {
 public:
  explicit LastStateCache(std::shared_ptr<const RigidTrajectory> inner) : inner_(std::move(inner)) {}
  RigidState at(const Instant& when) const override {
    if (!(valid_ && when.t == last_.t && when.piece_mid == last_.piece_mid)) {
      state_ = inner_->at(when);
      last_ = when;
      valid_ = true;
    }
    return state_;
  }
  double t_begin() const override { return inner_->t_begin(); }
  double t_end() const override { return inner_->t_end(); }
  std::vector<double> breakpoints() const override { return inner_->breakpoints(); }
  std::vector<double> knots() const override { return inner_->knots(); }

 private:
  std::shared_ptr<const RigidTrajectory> inner_;
  mutable Instant last_{0.0, 0.0};
  mutable RigidState state_;
  mutable bool valid_ = false;
};

/// With modal variables, replaces `sys` by the modal system over it; the returned object
/// must outlive the integration (null for physical variables: `sys` is left as it is).
std::unique_ptr<ModalVariables> use_variables(SimulationOptions::Variables v, const FlexibleBody& body,
                                              OdeSystem& sys, std::shared_ptr<const RigidTrajectory> frame) {
  if (v != SimulationOptions::Variables::Modal) return nullptr;
  auto modal = std::make_unique<ModalVariables>(body, sys.rhs, std::move(frame));
  OdeSystem over = modal->system(sys.last_error);
  over.quadrature_dim = sys.quadrature_dim;  // both see the physical state
  over.quadrature = std::move(sys.quadrature);
  over.range_check = std::move(sys.range_check);
  sys = std::move(over);
  return modal;
}

}  // namespace

Eigen::MatrixXd deflection_sampler(const FlexibleBody& body, int points) {
  const double a = body.beam().x_left(), b = body.beam().x_right();
  Eigen::MatrixXd P(points, body.n());
  for (int i = 0; i < points; ++i) P.row(i) = body.basis().value(i + 1 == points ? b : a + (b - a) * i / (points - 1));
  return P;
}

namespace detail {

namespace {
/// The rotary inertia about o that the frame keeps by itself at rest, as a share of I_o:
/// 1 / ((𝕄_b(0)⁻¹)_θθ I_o), what a moment at o meets when R and q move freely. Shape
/// functions that nearly contain a rotation about o leave it small (docs/theory.md
/// section 14): 1.4e-3 with the paper's six functions, 4e-5 with twenty.
double frame_inertia_fraction(const FlexibleBody& body) {
  const Eigen::MatrixXd M0 = body.mass_matrix(0.0, Eigen::VectorXd::Zero(body.n()));
  const double inverse_tt = M0.ldlt().solve(Eigen::VectorXd::Unit(M0.rows(), 2))(2);
  return 1.0 / (inverse_tt * M0(2, 2));
}
}  // namespace

std::function<std::string()> mass_matrix_failure(const FlexibleBody& body) {
  if (!body.geometric_stiffening())
    return [] { return std::string("the mass matrix lost positive definiteness (state out of range)"); };
  auto share = std::make_shared<std::optional<double>>();  // found at the first failure, kept
  return [&body, share] {
    if (!*share) *share = frame_inertia_fraction(body);
    return "the mass matrix came near singular or indefinite (the second-order kinetic energy no longer holds: "
           "state out of range; at rest the frame keeps by itself " +
           util::format_number(**share, 2) +
           " of the rotary inertia about o, and the smaller that share, the smaller the deflections the second-order "
           "model takes: it falls as noa grows, so fewer shape functions widen the range, docs/theory.md section 14)";
  };
}

std::function<std::string(const Instant&, const Eigen::Ref<const Eigen::VectorXd>&)> deflection_check(
    const FlexibleBody& body, const SimulationOptions& options, int q_offset, const Eigen::MatrixXd* to_q) {
  const Eigen::MatrixXd P = to_q ? Eigen::MatrixXd(deflection_sampler(body) * *to_q) : deflection_sampler(body);
  const double length = body.beam().x_right() - body.beam().x_left();
  const double limit = options.max_deflection_ratio * length;
  const int n = body.n();
  return [P, limit, length, n, q_offset](const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x) {
    const double u = (P * x.segment(q_offset, n)).cwiseAbs().maxCoeff();
    if (u <= limit) return std::string();
    return "the elastic deflection reached " + util::format_number(u, 4) + " m, " +
           util::format_number(u / length, 3) +
           " times the beam's length: the response grows without bound (out of the model's range)";
  };
}

}  // namespace detail

std::vector<FieldProblem> problems(const SimulationOptions& o) {
  const auto num = [](double v) { return util::format_number(v, 10); };
  std::vector<FieldProblem> p;
  if (!(o.duration_s > 0.0) || !std::isfinite(o.duration_s))
    p.push_back({"duration_s", "duration_s = " + num(o.duration_s) + ", expected a finite value > 0"});
  if (!(o.output_step_s > 0.0))
    p.push_back({"output_step_s", "output_step_s = " + num(o.output_step_s) + ", expected > 0"});
  else if (!(o.output_step_s <= o.duration_s))
    p.push_back({"output_step_s", "output_step_s = " + num(o.output_step_s) + " exceeds duration_s = " +
                                      num(o.duration_s) + ", expected output_step_s <= duration_s"});
  if (!(o.trajectory_step_s >= 0.0) || !std::isfinite(o.trajectory_step_s))
    p.push_back({"trajectory_step_s", "trajectory_step_s = " + num(o.trajectory_step_s) +
                                          ", expected a finite value > 0, or 0 for the automatic step"});
  if (!(o.max_deflection_ratio > 0.0))
    p.push_back({"max_deflection_ratio", "max_deflection_ratio = " + num(o.max_deflection_ratio) + ", expected > 0"});
  if (o.first_order_variables == SimulationOptions::Variables::RestModes)
    p.push_back({"first_order_variables", "first_order_variables = rest_modes: the full model's only (its mass matrix "
                                          "is what the coordinates simplify), expected physical or modal"});
  for (const FieldProblem& q : problems(o.integrator)) p.push_back({"integrator." + q.field, "integrator." + q.message});
  return p;
}

void validate(const SimulationOptions& o) { throw_if_any("simulation options", problems(o)); }

std::vector<double> output_times(const SimulationOptions& o) {
  validate(o);
  const long steps = std::lround(std::ceil(o.duration_s / o.output_step_s - 1e-9));
  std::vector<double> t;
  for (long i = 0; i < steps; ++i) t.push_back(i * o.output_step_s);
  t.push_back(o.duration_s);
  return t;
}

namespace {
constexpr double kTrajectoryStep_s = 1e-3;        // the integrator's automatic sampling
constexpr double kTaylorTrajectoryStep_s = 5e-3;  // the Taylor solver's (docs/benchmarks.md)
}  // namespace

double trajectory_step(const SimulationOptions& o) {
  const double automatic =
      o.first_order_solver == SimulationOptions::FirstOrderSolver::Taylor ? kTaylorTrajectoryStep_s : kTrajectoryStep_s;
  return std::min(o.trajectory_step_s > 0.0 ? o.trajectory_step_s : automatic, o.output_step_s);
}

SimulationOptions with_reusable_nominal(SimulationOptions o) {
  if (!(o.trajectory_step_s > 0.0)) o.trajectory_step_s = kTrajectoryStep_s;
  return o;
}

SimulationResult simulate_full(const FlexibleBody& body, const Excitation& excitation, const SimulationOptions& options,
                               const Eigen::VectorXd& x_initial) {
  const auto t0 = Clock::now();
  validate(options);
  const bool rest_modes = options.full_variables == SimulationOptions::Variables::RestModes;
  std::optional<FullModel> model;                     // the state [z, z']
  std::unique_ptr<const detail::RestModeModel> rest;  // or q taken to the modes at rest
  if (rest_modes)
    rest = std::make_unique<const detail::RestModeModel>(body);
  else
    model.emplace(body);
  const int N = body.dofs(), ne = static_cast<int>(body.elements().size());
  Eigen::VectorXd x0 = x_initial.size() ? x_initial : Eigen::VectorXd::Zero(2 * N);
  if (x0.size() != 2 * N)
    throw std::invalid_argument("simulate_full: expected an initial state of size " + std::to_string(2 * N) +
                                ", got " + std::to_string(x0.size()));
  auto u = std::make_shared<Eigen::VectorXd>(ne);
  OdeSystem sys;
  sys.dim = 2 * N;
  // the mass matrix left the model's range at the last evaluation (the explicit pairs
  // reject a trial step the model refuses and go on, so only the last one counts)
  auto singular = std::make_shared<bool>(false);
  // x' of either model (FullModel, or RestModeModel on its own state) under the loads
  auto model_rhs = [&excitation, u, singular](const auto* m) {
    auto data = std::make_shared<std::decay_t<decltype(m->create_data())>>(m->create_data());
    return [m, &excitation, data, u, singular](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                                               Eigen::Ref<Eigen::VectorXd> xd) {
      detail::evaluate_commands(excitation, at, *u);
      *singular = !m->rhs(*data, x, *u);
      if (*singular) return false;
      xd = data->x_dot;
      return true;
    };
  };
  if (rest)
    sys.rhs = model_rhs(rest.get());
  else
    sys.rhs = model_rhs(&*model);
  sys.last_error = detail::mass_matrix_failure(body);
  sys.range_check = detail::deflection_check(body, options, 3, rest ? &rest->modes() : nullptr);
  // Work of the loads and the damping, ż·(G − D ż), for the energy balance (outside the
  // error test: the states are the same with or without it). Not in modal variables: their
  // steps span many periods of the free oscillation, which the power then aliases (3 % off
  // on the paper's force pulse), and an error test of its own would change the steps. The
  // power is the same number in rest-mode coordinates, from the force and damping there.
  auto uq = std::make_shared<Eigen::VectorXd>(ne);
  auto Gq = std::make_shared<Eigen::VectorXd>(N);
  if (options.energy_balance && options.full_variables != SimulationOptions::Variables::Modal)
    sys.quadrature_dim = 1;
  sys.quadrature = [&body, &excitation, m = rest.get(), uq, Gq, N](
                       const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> w) {
    detail::evaluate_commands(excitation, at, *uq);
    const auto zd = x.tail(N);
    if (m)
      m->generalized_force(x(2), x.segment(3, N - 3), *uq, *Gq);
    else
      detail::generalized_force(body, x(2), x.segment(3, N - 3), *uq, *Gq);
    double p = zd.dot(*Gq);
    if (body.damped()) p -= m ? m->damping_power(zd) : zd.dot(body.damping() * zd);
    w(0) = p;
    return true;
  };
  const auto modal = use_variables(options.full_variables, body, sys, nullptr);
  if (rest) x0 = rest->to_rest_modes(x0);
  IntegrationResult ir =
      integrate(sys, x0, output_times(options), breakpoints_within(excitation, options.duration_s), options.integrator);
  if (rest) {  // the outputs in physical coordinates
    Eigen::VectorXd x(2 * N);
    for (Eigen::Index i = 0; i < ir.x.rows(); ++i) {
      rest->to_physical(ir.x.row(i).transpose(), x);
      ir.x.row(i) = x.transpose();
    }
  }
  SimulationResult r;
  r.status = ir.status == IntegrationStatus::Failed && *singular ? IntegrationStatus::OutOfRange : ir.status;
  r.message = ir.message;
  r.t = ir.t;
  r.z = ir.x.leftCols(N);
  r.z_dot = ir.x.rightCols(N);
  if (sys.quadrature_dim == 1) r.work_J = ir.quadrature.col(0);
  r.rhs_evaluations = ir.rhs_evaluations;
  r.steps = ir.steps;
  r.wall_time_s = seconds_since(t0);
  return r;
}

namespace {

/// The first-order pass by Taylor series (sim/ltv_taylor.hpp).
IntegrationResult taylor_first_order(
    const FlexibleBody& body, const Excitation& excitation, const RigidTrajectory& nominal,
    const SimulationResult& zero_order, const std::vector<double>& outs, const std::vector<double>& cuts,
    const SimulationOptions& options,
    const std::function<std::string(const Instant&, const Eigen::Ref<const Eigen::VectorXd>&)>& range_check) {
  // Sizes for the form's check: the nominal motion's largest rate and accelerations.
  double rate = 0.0, accel = 0.0, command = 0.0;
  Eigen::VectorXd u(static_cast<Eigen::Index>(body.elements().size()));
  for (Eigen::Index i = 0; i < zero_order.t.size(); ++i) {
    const Instant at = Instant::at(zero_order.t(i));
    const RigidState s = nominal.at(at);
    rate = std::max(rate, std::abs(s.vel(2)));
    accel = std::max(accel, s.acc.cwiseAbs().maxCoeff());
    detail::evaluate_commands(excitation, at, u);
    if (u.size()) command = std::max(command, u.cwiseAbs().maxCoeff());
  }
  const detail::LtvForm form = detail::ltv_form(body, rate, accel, command);
  if (!form.unsupported.empty()) {
    IntegrationResult r;
    r.status = IntegrationStatus::Failed;
    r.message = "first_order_solver = taylor: " + form.unsupported;
    r.failure_time = outs.front();
    return r;
  }
  detail::LtvCoefficients c;
  c.nominal = &nominal;
  c.scale.setOnes(6 + 3 * u.size());
  c.scale(1) = std::max(rate, 1e-300);
  c.scale(2) = std::max(rate * rate, 1e-300);
  c.scale.segment(3, 3).setConstant(std::max(accel, 1e-300));
  c.scale.tail(3 * u.size()).setConstant(std::max(command, 1e-300));
  c.commands = [&excitation](const Instant& at, Eigen::Ref<Eigen::VectorXd> v) {
    detail::evaluate_commands(excitation, at, v);
  };
  const int order = 50;  // docs/benchmarks.md: fewest terms at NOA 20 and rtol 1e-8 (30-80 tried)
  return detail::integrate_ltv_taylor(form, c, outs, cuts, options.integrator, order, range_check);
}

}  // namespace

PerturbationResult simulate_perturbation(const FlexibleBody& body, const Excitation& excitation,
                                         const SimulationOptions& options) {
  const auto t_start = Clock::now();
  const int ne = static_cast<int>(body.elements().size());
  const ZeroOrderModel zero(body);
  PerturbationResult out;
  const std::vector<double> outs = output_times(options);
  const std::vector<double> cuts = breakpoints_within(excitation, options.duration_s);

  // 1. Zero-order motion, sampled on each smooth piece for the rigid trajectory.
  std::vector<double> edges{0.0};
  edges.insert(edges.end(), cuts.begin(), cuts.end());
  edges.push_back(options.duration_s);
  const double h = trajectory_step(options);
  std::vector<double> nodes;
  std::vector<std::size_t> piece_first;  // index in nodes of each piece's first node
  for (std::size_t p = 0; p + 1 < edges.size(); ++p) {
    const double a = edges[p], b = edges[p + 1];
    const long m = std::max(1L, std::lround(std::ceil((b - a) / h)));
    piece_first.push_back(nodes.empty() ? 0 : nodes.size() - 1);
    for (long i = (p == 0 ? 0 : 1); i <= m; ++i) nodes.push_back(i == m ? b : a + (b - a) * i / m);
  }
  std::vector<double> all = nodes;
  all.insert(all.end(), outs.begin(), outs.end());
  std::sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());

  auto u = std::make_shared<Eigen::VectorXd>(ne);
  OdeSystem zsys;
  zsys.dim = 6;
  zsys.rhs = [&zero, &excitation, u](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                                     Eigen::Ref<Eigen::VectorXd> xd) {
    detail::evaluate_commands(excitation, at, *u);
    xd = zero.rhs(x, *u);
    return util::all_finite(xd);
  };
  // The first-order model takes θ0'' and R0'' from the quintic interpolant of these
  // samples, which multiplies their errors by ~60/h²: at rtol 1e-8 the wiggle right after
  // a restart reached 1% of θ0'' (0.1 of 12 rad/s² on the paper's moment pulse). The six
  // rigid states are cheap, so they are integrated to 1e-12 whatever the design asks.
  IntegratorOptions zero_options = options.integrator;
  zero_options.rtol = std::min(zero_options.rtol, 1e-12);
  zero_options.atol = std::min(zero_options.atol, 1e-14);
  zero_options.progress = nullptr;  // a few dozen steps; progress is the first-order pass's
  const IntegrationResult zr = integrate(zsys, Eigen::VectorXd::Zero(6), all, cuts, zero_options);
  out.zero_order.status = zr.status;
  out.zero_order.message = zr.message;
  out.zero_order.rhs_evaluations = zr.rhs_evaluations;
  out.zero_order.steps = zr.steps;
  if (!zr.ok()) {
    out.total = out.zero_order;
    out.total.message = "zero-order simulation: " + zr.message;
    out.total.wall_time_s = seconds_since(t_start);
    return out;
  }
  auto state_at = [&](double t) {
    const auto it = std::lower_bound(all.begin(), all.end(), t);
    return Eigen::VectorXd(zr.x.row(it - all.begin()).transpose());
  };
  std::vector<SampledRigidTrajectory::Piece> pieces;
  for (std::size_t p = 0; p + 1 < edges.size(); ++p) {
    SampledRigidTrajectory::Piece pc;
    const double mid = 0.5 * (edges[p] + edges[p + 1]);
    for (std::size_t i = piece_first[p]; i < nodes.size() && nodes[i] <= edges[p + 1]; ++i) {
      const Eigen::VectorXd x = state_at(nodes[i]);
      detail::evaluate_commands(excitation, {nodes[i], mid}, *u);  // this piece's side of any jump
      RigidState s;
      s.pos = x.head<3>();
      s.vel = x.tail<3>();
      s.acc = zero.acceleration(x, *u);
      pc.t.push_back(nodes[i]);
      pc.samples.push_back(s);
    }
    pieces.push_back(std::move(pc));
  }
  out.nominal = std::make_shared<SampledRigidTrajectory>(std::move(pieces));

  PerturbationResult about = simulate_perturbation_about(body, excitation, out.nominal, options);
  about.zero_order.rhs_evaluations = zr.rhs_evaluations;
  about.zero_order.steps = zr.steps;
  about.total.rhs_evaluations += zr.rhs_evaluations;
  about.total.steps += zr.steps;
  about.total.wall_time_s = seconds_since(t_start);
  return about;
}

PerturbationResult simulate_perturbation_about(const FlexibleBody& body, const Excitation& excitation,
                                               std::shared_ptr<const RigidTrajectory> nominal,
                                               const SimulationOptions& options) {
  const auto t_start = Clock::now();
  const int N = body.dofs();
  const std::vector<double> outs = output_times(options);
  std::vector<double> cuts = breakpoints_within(excitation, options.duration_s);
  for (double b : nominal->breakpoints())
    if (b > 0.0 && b < options.duration_s) cuts.push_back(b);
  PerturbationResult out;
  out.nominal = nominal;
  out.zero_order.status = IntegrationStatus::Completed;
  // Zero-order results at the output times.
  const int T = static_cast<int>(outs.size());
  out.zero_order.t = Eigen::Map<const Eigen::VectorXd>(outs.data(), T);
  out.zero_order.z = Eigen::MatrixXd::Zero(T, N);
  out.zero_order.z_dot = Eigen::MatrixXd::Zero(T, N);
  for (int i = 0; i < T; ++i) {
    const RigidState s = nominal->at(Instant::at(outs[i]));
    out.zero_order.z.row(i).head<3>() = s.pos.transpose();
    out.zero_order.z_dot.row(i).head<3>() = s.vel.transpose();
  }

  // 2. First-order motion about it, open loop (u1 = 0).
  const auto cached = std::make_shared<const LastStateCache>(nominal);
  const FirstOrderModel first(
      body, *cached,
      [&excitation](const Instant& at, Eigen::Ref<Eigen::VectorXd> c) { detail::evaluate_commands(excitation, at, c); },
      {});
  auto data = std::make_shared<FirstOrderModel::Data>(first.create_data());
  OdeSystem fsys;
  fsys.dim = 2 * N;
  const Eigen::VectorXd none(0);
  fsys.rhs = [&first, &none, data](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x,
                                   Eigen::Ref<Eigen::VectorXd> xd) {
    xd = first.rhs(*data, at, x, none);
    return util::all_finite(xd);
  };
  fsys.jacobian = [&first, data](const Instant& at, const Eigen::Ref<const Eigen::VectorXd>&,
                                 Eigen::Ref<Eigen::MatrixXd> J) {
    const StateSpace& ss = first.state_space(*data, at);
    J = ss.A;
    return ss.A.allFinite();
  };
  fsys.last_error = [] { return std::string("the first-order right-hand side is not finite"); };
  fsys.range_check = detail::deflection_check(body, options, 3);
  IntegrationResult fr;
  if (options.first_order_solver == SimulationOptions::FirstOrderSolver::Taylor) {
    fr = taylor_first_order(body, excitation, *nominal, out.zero_order, outs, cuts, options, fsys.range_check);
  } else {
    const auto modal = use_variables(options.first_order_variables, body, fsys, cached);
    fr = integrate(fsys, Eigen::VectorXd::Zero(2 * N), outs, cuts, options.integrator);
  }
  out.first_order_rhs_evaluations = fr.rhs_evaluations;
  SimulationResult& tot = out.total;
  tot.status = fr.status;
  tot.message = fr.ok() ? "" : "first-order simulation: " + fr.message;
  tot.t = fr.t;
  const int reached = static_cast<int>(fr.t.size());
  tot.z = fr.x.leftCols(N) + out.zero_order.z.topRows(reached);
  tot.z_dot = fr.x.rightCols(N) + out.zero_order.z_dot.topRows(reached);
  tot.rhs_evaluations = fr.rhs_evaluations;
  tot.steps = fr.steps;
  tot.wall_time_s = seconds_since(t_start);
  return out;
}

SimulationOptions error_reference_options(const SimulationOptions& options) {
  SimulationOptions o = options;
  o.integrator.rtol = std::max(options.integrator.rtol / kErrorEstimateFactor, 1e-14);
  o.integrator.atol = options.integrator.atol / kErrorEstimateFactor;
  o.integrator.progress = nullptr;
  return o;
}

GlobalErrorEstimate compare_runs(const SimulationResult& run, const SimulationResult& reference,
                                 const SimulationOptions& reference_options) {
  GlobalErrorEstimate e;
  e.rtol = reference_options.integrator.rtol;
  e.atol = reference_options.integrator.atol;
  e.rhs_evaluations = reference.rhs_evaluations;
  e.wall_time_s = reference.wall_time_s;
  if (!run.ok()) {
    e.message = "the run itself failed";
    return e;
  }
  if (!reference.ok()) {
    e.message = "the run at rtol " + util::format_number(e.rtol, 3) + " failed: " + reference.message;
    return e;
  }
  if (reference.t.size() != run.t.size() || reference.z.cols() != run.z.cols() ||
      !(reference.t.array() == run.t.array()).all()) {
    e.message = "the two runs have different output times";
    return e;
  }
  const Eigen::MatrixXd dz = (run.z - reference.z).cwiseAbs();
  if (!dz.allFinite() || !(run.z_dot - reference.z_dot).allFinite()) {
    e.message = "the difference of the two runs is not finite";
    return e;
  }
  const int n = static_cast<int>(dz.cols()) - 3;
  double worst = -1.0;
  for (Eigen::Index i = 0; i < dz.rows(); ++i) {
    const double row = dz.row(i).maxCoeff();
    if (row > worst) {
      worst = row;
      e.worst_time_s = run.t(i);
    }
  }
  e.R_m = dz.leftCols(2).maxCoeff();
  e.theta_rad = dz.col(2).maxCoeff();
  e.q = n > 0 ? dz.rightCols(n).maxCoeff() : 0.0;
  e.rates = (run.z_dot - reference.z_dot).cwiseAbs().maxCoeff();
  e.available = true;
  return e;
}

}  // namespace freeflex
