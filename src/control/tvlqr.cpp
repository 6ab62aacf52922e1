// TV-LQR (control/tvlqr.hpp): validation, the grid of stored gains, the backward sweep of
// the Riccati flow through the shared CVODES wrapper, and the law's interpolation.
#include "freeflex/control/tvlqr.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "control/riccati_flow.hpp"
#include "sim/cvodes.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string fmt(double v) { return util::format_number(v, 10); }

/// The first problem of the options that does not depend on the system, or "".
std::string options_problem(const TvlqrOptions& o) {
  if (!(o.grid_step_s > 0.0) || !std::isfinite(o.grid_step_s))
    return "grid_step_s = " + fmt(o.grid_step_s) + ", must be finite and > 0";
  if (!(o.rtol > 0.0) || !(o.atol > 0.0)) return "rtol and atol must be > 0, got " + fmt(o.rtol) + ", " + fmt(o.atol);
  if (o.max_steps <= 0) return "max_steps must be > 0";
  if (!(o.modal_max_condition >= 0.0)) return "modal_max_condition = " + fmt(o.modal_max_condition) + ", must be >= 0";
  for (double b : o.breakpoints)
    if (!std::isfinite(b)) return "breakpoints must be finite";
  return "";
}

void validate(const LtvSystem& sys, double t0, double tf, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R,
              const TvlqrOptions& o) {
  const std::string w = "tvlqr";
  auto fail = [&](const std::string& what) { throw std::invalid_argument(w + ": " + what); };
  if (sys.state_size < 1) fail("the system must have state_size >= 1, got " + std::to_string(sys.state_size));
  if (sys.input_size < 1) fail("the system must have at least one input, got " + std::to_string(sys.input_size));
  if (!sys.state_space) fail("the system's state_space function is empty");
  if (!std::isfinite(t0) || !std::isfinite(tf)) fail("t0 and tf must be finite");
  if (!(tf > t0)) fail("tf = " + fmt(tf) + " must be > t0 = " + fmt(t0));
  const std::string problem = options_problem(o);
  if (!problem.empty()) fail(problem);
  check_positive_semidefinite(Q, sys.state_size, "Q", w);
  check_positive_definite(R, sys.input_size, "R", w);
  if (o.Qf) check_positive_semidefinite(*o.Qf, sys.state_size, "Qf", w);
}

/// A user's LtvSystem: each evaluation returns a new StateSpace.
class FunctionEvaluator : public detail::LtvEvaluator {
 public:
  explicit FunctionEvaluator(const LtvSystem& sys) : sys_(sys) {}
  const StateSpace& eval(const Instant& at) override {
    value_ = sys_.state_space(at);
    return value_;
  }

 private:
  const LtvSystem& sys_;
  StateSpace value_;
};

/// The first-order model through its workspace: no allocation per evaluation.
class ModelEvaluator : public detail::LtvEvaluator {
 public:
  explicit ModelEvaluator(const FirstOrderModel& model) : model_(model), data_(model.create_data()) {}
  const StateSpace& eval(const Instant& at) override { return model_.state_space(data_, at); }

 private:
  const FirstOrderModel& model_;
  FirstOrderModel::Data data_;
};

/// The sweep itself, for any evaluator of the model (arguments validated).
TvlqrResult sweep(detail::LtvEvaluator& model, int n, int m, const std::vector<double>& model_breakpoints, double t0,
                  double tf, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R, const TvlqrOptions& o) {
  using namespace detail;
  const auto clock0 = std::chrono::steady_clock::now();
  TvlqrResult res;

  // Pieces [bounds_k, bounds_k+1] and the output grid (every bound is a grid time).
  const double span = tf - t0, merge = 1e-10 * span;
  std::vector<double> bounds{t0};
  {
    std::vector<double> b;
    for (double x : model_breakpoints)
      if (x > t0 + merge && x < tf - merge) b.push_back(x);
    for (double x : o.breakpoints)
      if (x > t0 + merge && x < tf - merge) b.push_back(x);
    std::sort(b.begin(), b.end());
    for (double x : b)
      if (x - bounds.back() > merge) bounds.push_back(x);
    bounds.push_back(tf);
  }
  std::vector<double> grid = bounds;
  const long cells = std::lround(std::ceil(span / o.grid_step_s - 1e-9));
  for (long i = 1; i < cells; ++i) grid.push_back(t0 + i * o.grid_step_s);
  std::sort(grid.begin(), grid.end());
  {
    std::vector<double> g2;
    for (double x : grid) {
      const bool is_bound = std::binary_search(bounds.begin(), bounds.end(), x);
      if (!g2.empty() && x - g2.back() <= merge) {
        if (is_bound) g2.back() = x;  // keep the breakpoint itself
        continue;
      }
      g2.push_back(x);
    }
    grid = g2;
  }
  const int G = static_cast<int>(grid.size());

  RiccatiData d;
  d.model = &model;
  d.tf = tf;
  d.n = n;
  d.m = m;
  d.Rllt.compute(0.5 * (R + R.transpose()));
  d.max_condition = o.modal_max_condition;
  d.piece_mid_t = 0.5 * (bounds[bounds.size() - 2] + bounds.back());

  // Terminal weight.
  if (o.Qf) {
    res.Qf = 0.5 * (*o.Qf + o.Qf->transpose());
  } else {
    if (!d.eval(tf)) {
      res.status = TvlqrResult::Status::TerminalCareFailed;
      res.message = "terminal CARE: " + d.error;
      return res;
    }
    CareOptions co;
    co.restrict_to_controllable = true;
    CareResult care = solve_care(d.A(), d.B(), Q, R, co);
    if (!care.ok()) {
      res.status = TvlqrResult::Status::TerminalCareFailed;
      res.message = "terminal CARE at tf = " + fmt(tf) + " s failed: " + care.message;
      res.terminal_care = std::move(care);
      return res;
    }
    res.Qf = care.P;
    res.terminal_care = std::move(care);
  }
  d.sigma = std::max(res.Qf.cwiseAbs().maxCoeff(), Q.cwiseAbs().maxCoeff());
  if (!(d.sigma > 0.0)) d.sigma = 1.0;
  d.Qs = 0.5 * (Q + Q.transpose()) / d.sigma;

  res.t = grid;
  res.K.assign(G, Eigen::MatrixXd());
  res.feedforward.setZero(G, m);
  if (o.store_riccati) res.P.assign(G, Eigen::MatrixXd());

  const int nt = tri_size(n), dim = nt + n + 1;
  cvodes::Integrator cv(dim, cvodes::Integrator::Method::Bdf, "solve_tvlqr");
  double* y = cv.state();
  Eigen::Map<Eigen::VectorXd>(y, dim).setZero();
  pack(res.Qf / d.sigma, y);

  Eigen::MatrixXd Psym, Krec;  // scratch of record()
  Eigen::VectorXd ffrec;
  auto record = [&](int idx) -> bool {
    const double t = grid[idx];
    if (!d.eval(t)) return false;
    unpack(y, n, Psym);
    Psym *= d.sigma;
    Eigen::Map<const Eigen::VectorXd> sh(y + nt, n);
    Krec.noalias() = d.B().transpose() * Psym;
    d.Rllt.solveInPlace(Krec);
    res.K[idx] = Krec;
    ffrec.noalias() = d.B().transpose() * sh;
    d.Rllt.solveInPlace(ffrec);
    res.feedforward.row(idx) = -d.sigma * ffrec.transpose();
    if (o.store_riccati) res.P[idx] = Psym;
    if (idx == 0) {
      res.P0 = Psym;
      res.s0 = d.sigma * sh;
      res.c0 = d.sigma * y[nt + n];
    }
    return true;
  };
  auto finish = [&](TvlqrResult::Status st, std::string msg) {
    res.status = st;
    res.message = std::move(msg);
    res.preconditioner_setups = d.setups;
    res.modal_setups = d.modal_setups;
    res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return res;
  };

  cv.init(freeflex_riccati_rhs, 0.0, &d);
  cv.scalar_tolerances(o.rtol, o.atol);
  cv.max_num_steps(o.max_steps);
  DirectSolverContent direct{&d, cv.memory()};
  if (o.newton_solver == TvlqrOptions::NewtonSolver::Lyapunov)
    cv.matrix_embedded(make_direct_solver(cv.context(), &direct));
  else
    cv.gmres(10, freeflex_riccati_psetup, freeflex_riccati_psolve, freeflex_riccati_jtsetup, freeflex_riccati_jtimes);

  auto add_stats = [&]() {
    const cvodes::Counters c = cv.counters();
    res.steps += c.steps;
    res.rhs_evaluations += c.rhs_evaluations;
    res.linear_iterations += c.linear_iterations;
  };

  const long long work = riccati_step_work(n);
  int idx = G - 1;
  if (!record(idx)) return finish(TvlqrResult::Status::IntegrationFailed, d.error);
  --idx;
  const int pieces = static_cast<int>(bounds.size()) - 1;
  for (int p = pieces - 1; p >= 0; --p) {
    const double a_t = bounds[p], b_t = bounds[p + 1];
    const double tau_a = tf - b_t, tau_b = tf - a_t;
    d.piece_mid_t = 0.5 * (a_t + b_t);
    d.cached = false;
    d.have_pre = false;  // the model may jump at a breakpoint: refresh the frozen closed loop
    if (p != pieces - 1) cv.reinit(tau_a);
    cv.stop_time(tau_b);
    while (idx >= 0 && grid[idx] >= a_t) {
      const double tau_out = (grid[idx] == a_t) ? tau_b : tf - grid[idx];
      bool by_budget = false;
      const cvodes::Integrator::Advance step = cv.advance(tau_out, o.max_steps, o.budget.get(), work, by_budget);
      const double tret = step.reached;
      if (step.flag == CV_TOO_MUCH_WORK && by_budget) {
        add_stats();
        return finish(TvlqrResult::Status::IntegrationFailed,
                      "stopped at t = " + fmt(tf - tret) + " s: " + o.budget->spent_message());
      }
      if (step.flag < 0) {
        add_stats();
        std::string msg = "CVODES failed at t = " + fmt(tf - tret) + " s: " + cvodes::Integrator::flag_name(step.flag);
        // CVODES's own message counts the backward time τ = tf - t.
        const std::string why = !d.error.empty()         ? d.error
                                : cv.last_error().empty() ? ""
                                                          : cv.last_error() + " [τ = tf - t]";
        if (!why.empty()) msg += " (" + why + ")";
        return finish(TvlqrResult::Status::IntegrationFailed, msg);
      }
      if (!Eigen::Map<const Eigen::VectorXd>(y, dim).allFinite()) {
        add_stats();
        return finish(TvlqrResult::Status::IntegrationFailed,
                      "the Riccati solution became non-finite at t = " + fmt(tf - tret) + " s");
      }
      if (!record(idx)) return finish(TvlqrResult::Status::IntegrationFailed, d.error);
      if (o.progress) o.progress(tf - grid[idx]);
      --idx;
    }
    add_stats();
  }
  return finish(TvlqrResult::Status::Solved, "solved");
}

}  // namespace

long long riccati_step_work(int n) {
  const long long m = std::max(1, n);
  return m * m * m;
}

void validate(const TvlqrOptions& options) {
  const std::string problem = options_problem(options);
  if (!problem.empty()) throw std::invalid_argument("tvlqr options: " + problem);
}

LtvSystem ltv_system(const FirstOrderModel& model) {
  LtvSystem s;
  s.state_size = model.state_size();
  s.input_size = model.input_size();
  s.state_space = [&model](const Instant& at) { return model.state_space(at); };
  s.breakpoints = model.nominal().breakpoints();
  return s;
}

TvlqrResult solve_tvlqr(const FirstOrderModel& model, double t0, double tf, const Eigen::MatrixXd& Q,
                        const Eigen::MatrixXd& R, const TvlqrOptions& options) {
  const RigidTrajectory& nom = model.nominal();
  const double span = std::max({1.0, std::abs(nom.t_begin()), std::abs(nom.t_end())});
  if (t0 < nom.t_begin() - 1e-12 * span)
    throw std::invalid_argument("tvlqr: t0 = " + fmt(t0) + " s is before the nominal motion begins (" +
                                fmt(nom.t_begin()) + " s)");
  if (tf < nom.t_end() - 1e-12 * span)
    throw std::invalid_argument("tvlqr: tf = " + fmt(tf) + " s ends before the nominal maneuver does (" +
                                fmt(nom.t_end()) + " s): the horizon must cover the maneuver");
  if (model.input_size() < 1)
    throw std::invalid_argument("tvlqr: the first-order model has no inputs (actuators); expected at least one");
  const LtvSystem sys = ltv_system(model);
  validate(sys, t0, tf, Q, R, options);
  ModelEvaluator evaluator(model);
  return sweep(evaluator, sys.state_size, sys.input_size, sys.breakpoints, t0, tf, Q, R, options);
}

TvlqrResult solve_tvlqr(const LtvSystem& sys, double t0, double tf, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R,
                        const TvlqrOptions& options) {
  validate(sys, t0, tf, Q, R, options);
  FunctionEvaluator evaluator(sys);
  return sweep(evaluator, sys.state_size, sys.input_size, sys.breakpoints, t0, tf, Q, R, options);
}

namespace {
/// Index i with t[i] <= time < t[i+1] (clamped) and the weight of t[i+1].
std::pair<int, double> locate(const std::vector<double>& t, double time) {
  if (t.size() < 2 || time <= t.front()) return {0, 0.0};
  if (time >= t.back()) return {static_cast<int>(t.size()) - 2, 1.0};
  const auto it = std::upper_bound(t.begin(), t.end(), time);
  const int i = static_cast<int>(it - t.begin()) - 1;
  return {i, (time - t[i]) / (t[i + 1] - t[i])};
}
}  // namespace

Eigen::MatrixXd TvlqrResult::gain(double time) const {
  if (K.empty()) throw std::logic_error("TvlqrResult::gain: no gains stored (the solve failed)");
  if (K.size() == 1) return K.front();
  const auto [i, w] = locate(t, time);
  return (1.0 - w) * K[i] + w * K[i + 1];
}

Eigen::VectorXd TvlqrResult::feedforward_at(double time) const {
  if (feedforward.rows() == 0) throw std::logic_error("TvlqrResult::feedforward_at: nothing stored (the solve failed)");
  if (feedforward.rows() == 1) return feedforward.row(0).transpose();
  const auto [i, w] = locate(t, time);
  return ((1.0 - w) * feedforward.row(i) + w * feedforward.row(i + 1)).transpose();
}

Eigen::VectorXd TvlqrResult::control(double time, const Eigen::Ref<const Eigen::VectorXd>& x1) const {
  const Eigen::MatrixXd Kt = gain(time);
  if (x1.size() != Kt.cols())
    throw std::invalid_argument("TvlqrResult::control: expected x1 of size " + std::to_string(Kt.cols()) + ", got " +
                                std::to_string(x1.size()));
  return -Kt * x1 + feedforward_at(time);
}

double TvlqrResult::predicted_cost(const Eigen::Ref<const Eigen::VectorXd>& x1) const {
  if (x1.size() != P0.rows())
    throw std::invalid_argument("TvlqrResult::predicted_cost: expected x1 of size " + std::to_string(P0.rows()) +
                                ", got " + std::to_string(x1.size()));
  return x1.dot(P0 * x1) + 2.0 * s0.dot(x1) + c0;
}

}  // namespace freeflex
