// TV-LQR (control/tvlqr.hpp): validation, the grid of stored gains and the terminal
// weight, the choice of sweep (control/tvlqr_sweep.hpp), and the law's interpolation.
#include "freeflex/control/tvlqr.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "control/tvlqr_sweep.hpp"
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

/// The grid, pieces and terminal weight of a problem (arguments validated), then the sweep
/// of the chosen method (control/tvlqr_sweep.hpp).
TvlqrResult sweep(detail::LtvEvaluator& model, int n, int m, const std::vector<double>& model_breakpoints, double t0,
                  double tf, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R, const TvlqrOptions& o,
                  const detail::RotatingFrame* frame) {
  using namespace detail;
  const auto clock0 = std::chrono::steady_clock::now();
  TvlqrResult res;
  auto done = [&]() -> TvlqrResult {
    res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock0).count();
    return std::move(res);
  };

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

  // Terminal weight: given, or the CARE solution of the model at tf.
  if (o.Qf) {
    res.Qf = 0.5 * (*o.Qf + o.Qf->transpose());
  } else {
    RiccatiData d;
    d.model = &model;
    d.tf = tf;
    d.n = n;
    d.m = m;
    d.Rllt.compute(0.5 * (R + R.transpose()));
    d.piece_mid_t = 0.5 * (bounds[bounds.size() - 2] + bounds.back());
    if (!d.eval(tf)) {
      res.status = TvlqrResult::Status::TerminalCareFailed;
      res.message = "terminal CARE: " + d.error;
      return done();
    }
    CareOptions co;
    co.restrict_to_controllable = true;
    CareResult care = solve_care(d.A(), d.B(), Q, R, co);
    if (!care.ok()) {
      res.status = TvlqrResult::Status::TerminalCareFailed;
      res.message = "terminal CARE at tf = " + fmt(tf) + " s failed: " + care.message;
      res.terminal_care = std::move(care);
      return done();
    }
    res.Qf = care.P;
    res.terminal_care = std::move(care);
  }
  res.t = grid;
  res.K.assign(G, Eigen::MatrixXd());
  res.feedforward.setZero(G, m);
  if (o.store_riccati) res.P.assign(G, Eigen::MatrixXd());

  Sweep sw;
  sw.model = &model;
  sw.n = n;
  sw.m = m;
  sw.t0 = t0;
  sw.tf = tf;
  sw.bounds = bounds;
  sw.grid = grid;
  sw.Q = 0.5 * (Q + Q.transpose());
  sw.R = 0.5 * (R + R.transpose());
  sw.options = &o;
  sw.frame = frame;
  sw.result = &res;
  // modal_max_condition = 0 allows no modal form: the exponential sweep would be BDF throughout
  const bool exponential = o.modal_max_condition > 0.0 &&
                           (o.method == TvlqrOptions::Method::Exponential ||
                            (o.method == TvlqrOptions::Method::Auto && n >= TvlqrOptions::kAutoExponentialStates));
  res.method = exponential ? TvlqrOptions::Method::Exponential : TvlqrOptions::Method::Bdf;
  if (exponential)
    sweep_exponential(sw);
  else
    sweep_bdf(sw);
  return done();
}

/// The first-order model's rotating frame: its x1 = [R1, θ1, q, R1', θ1', q'] has the
/// displacement and velocity of o in inertial axes, its dynamics are body-fixed. Used when
/// Q is unchanged by the rotation (as vibration_weight's is), so that the weight needs no
/// transformation; else null (the exponential sweep then takes shorter steps).
std::unique_ptr<detail::RotatingFrame> rotating_frame(const FirstOrderModel& model, const Eigen::MatrixXd& Q) {
  const int N = model.body().dofs();
  auto f = std::make_unique<detail::RotatingFrame>();
  f->pairs = {0, N};
  Eigen::MatrixXd T = Eigen::MatrixXd::Identity(2 * N, 2 * N);
  const double c = std::cos(0.7), s = std::sin(0.7);  // a generic angle
  for (int i : f->pairs) T.block(i, i, 2, 2) << c, -s, s, c;
  const Eigen::MatrixXd Qs = 0.5 * (Q + Q.transpose());
  if (!((T.transpose() * Qs * T - Qs).norm() <= 1e-12 * Qs.norm())) return nullptr;
  const RigidTrajectory& nom = model.nominal();
  f->angle = [&nom](const Instant& at, double& angle, double& rate) {
    const RigidState st = nom.at(at);
    angle = st.pos(2);
    rate = st.vel(2);
  };
  return f;
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
  const std::unique_ptr<detail::RotatingFrame> frame = rotating_frame(model, Q);
  return sweep(evaluator, sys.state_size, sys.input_size, sys.breakpoints, t0, tf, Q, R, options, frame.get());
}

TvlqrResult solve_tvlqr(const LtvSystem& sys, double t0, double tf, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R,
                        const TvlqrOptions& options) {
  validate(sys, t0, tf, Q, R, options);
  FunctionEvaluator evaluator(sys);
  return sweep(evaluator, sys.state_size, sys.input_size, sys.breakpoints, t0, tf, Q, R, options, nullptr);
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
