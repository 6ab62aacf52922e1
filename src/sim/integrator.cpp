// ODE integration cut into pieces at breakpoints (docs/theory.md section 8): the driver
// that records output times, maps integration variables and checks ranges, whichever
// stepper (CVODES or an explicit Runge-Kutta pair, sim/stepper.hpp) advances.
#include "freeflex/sim/integrator.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sim/stepper.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string fmt(double v) { return util::format_number(v, 12); }

void fail(const std::string& what) { throw std::invalid_argument("freeflex::integrate: " + what); }


void validate(const OdeSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x0,
              const std::vector<double>& output_times, const IntegratorOptions& options) {
  if (system.dim < 1) fail("expected system.dim >= 1, got " + std::to_string(system.dim));
  if (x0.size() != system.dim)
    fail("expected x0 of size system.dim = " + std::to_string(system.dim) + ", got " + std::to_string(x0.size()));
  if (!x0.allFinite()) fail("expected finite x0, got a non-finite entry");
  if (!system.rhs) fail("expected system.rhs to be set, got an empty function");
  if (output_times.empty()) fail("expected at least one output time, got none");
  for (std::size_t i = 0; i < output_times.size(); ++i) {
    if (!std::isfinite(output_times[i]))
      fail("expected finite output times, got " + fmt(output_times[i]) + " at index " + std::to_string(i));
    if (i > 0 && !(output_times[i] > output_times[i - 1]))
      fail("expected strictly ascending output times, got " + fmt(output_times[i - 1]) + " then " +
           fmt(output_times[i]) + " at index " + std::to_string(i));
  }
  const std::vector<FieldProblem> p = problems(options);
  if (!p.empty()) fail(p.front().message);
}

}  // namespace

std::vector<FieldProblem> problems(const IntegratorOptions& o) {
  std::vector<FieldProblem> p;
  if (!(o.rtol > 0.0) || !std::isfinite(o.rtol)) p.push_back({"rtol", "rtol = " + fmt(o.rtol) + ", expected a finite value > 0"});
  if (!(o.atol > 0.0) || !std::isfinite(o.atol)) p.push_back({"atol", "atol = " + fmt(o.atol) + ", expected a finite value > 0"});
  if (!(o.max_step >= 0.0) || !std::isfinite(o.max_step))
    p.push_back({"max_step", "max_step = " + fmt(o.max_step) + ", expected a finite value >= 0 (0: no limit)"});
  if (o.max_steps <= 0) p.push_back({"max_steps", "max_steps = " + std::to_string(o.max_steps) + ", expected > 0"});
  if (o.max_total_steps < 0)
    p.push_back({"max_total_steps",
                 "max_total_steps = " + std::to_string(o.max_total_steps) + ", expected >= 0 (0: no limit)"});
  if (o.max_order < 0)
    p.push_back({"max_order", "max_order = " + std::to_string(o.max_order) + ", expected >= 0 (0: CVODE's default)"});
  return p;
}

std::string detail::user_message(const OdeSystem& system, const char* what) {
  std::string msg;
  if (system.last_error) {
    try {
      msg = system.last_error();
    } catch (...) {
      msg.clear();
    }
  }
  if (msg.empty()) msg = std::string(what) + " reported a failure";
  return msg;
}

void validate(const IntegratorOptions& options) { throw_if_any("integrator options", problems(options)); }

WorkBudget::WorkBudget(long long units, std::string owner) : total_(units), owner_(std::move(owner)) {
  if (units <= 0) throw std::invalid_argument("WorkBudget: units = " + std::to_string(units) + ", expected > 0");
}

long long WorkBudget::left() const { return std::max(0LL, total_ - spent_.load()); }

long WorkBudget::steps_left(long long step_work) const {
  const long long per = std::max(1LL, step_work);
  return static_cast<long>(std::min<long long>(left() / per, std::numeric_limits<long>::max()));
}

void WorkBudget::charge(long long units) {
  if (units > 0) spent_ += units;
}

std::string WorkBudget::spent_message() const {
  std::ostringstream os;
  os << owner_ << "'s work budget of " << total_
     << " units (integration steps weighted by the size of what they integrate; README, the \"(limits)\" row) is "
        "spent";
  return os.str();
}

long long step_work(long dim, IntegratorOptions::Method method) {
  const long long N = std::max(1L, dim / 2);
  const long long w = std::max(N * N, 400LL);
  switch (method) {
    case IntegratorOptions::Method::Bdf: return 3 * w;  // Newton iterations with dense solves
    case IntegratorOptions::Method::Dop853:
    case IntegratorOptions::Method::Verner98: return 10 * w;  // 12 to 16 right-hand sides a step, Adams 1.5 to 2
    default: return w;
  }
}

bool roundoff_span(double a, double b) {
  return b - a <= 4.0 * DBL_EPSILON * std::max(std::abs(a), std::abs(b)) || b - a < kMinSpan_s;
}

IntegrationResult integrate(const OdeSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x0,
                            const std::vector<double>& output_times, const std::vector<double>& breakpoints,
                            const IntegratorOptions& options) {
  validate(system, x0, output_times, options);

  const long n = system.dim;
  const std::size_t n_out = output_times.size();
  const double t0 = output_times.front();
  const double tend = output_times.back();

  const VariableChange& change = system.variables;
  if (change.active() && !change.to_x)
    throw std::invalid_argument("freeflex::integrate: variables.enter_piece is set but variables.to_x is not");
  if (change.active() && change.atol_scale.size() != 0 &&
      (change.atol_scale.size() != n || !(change.atol_scale.array() > 0.0).all() || !change.atol_scale.allFinite()))
    throw std::invalid_argument("freeflex::integrate: variables.atol_scale must be empty or " + std::to_string(n) +
                                " finite entries > 0");

  if (system.quadrature_dim < 0 || (system.quadrature_dim > 0 && !system.quadrature))
    throw std::invalid_argument("freeflex::integrate: quadrature_dim = " + std::to_string(system.quadrature_dim) +
                                ", expected 0, or > 0 with system.quadrature set");
  const int nq = system.quadrature_dim;

  IntegrationResult result;
  result.t.resize(static_cast<Eigen::Index>(n_out));
  result.x.resize(static_cast<Eigen::Index>(n_out), n);
  result.quadrature.setZero(static_cast<Eigen::Index>(n_out), nq);
  Eigen::VectorXd quad_now = Eigen::VectorXd::Zero(nq);  // the quadratures at the time last reached
  std::string out_of_range;                               // why the recorded state left the model's range
  Eigen::Index rows = 0;
  Eigen::VectorXd x_scratch(n);
  double piece_mid = t0;  // of the piece whose variables y currently holds
  // y -> x under the current piece's variables.
  auto physical = [&](double t, const double* y) -> const double* {
    if (!change.active()) return y;
    change.to_x(Instant{t, piece_mid}, Eigen::Map<const Eigen::VectorXd>(y, n), x_scratch);
    return x_scratch.data();
  };
  // Records the state at an output time; false when it is outside the model's range.
  auto record = [&](double t, const double* y) {
    result.t(rows) = t;
    result.x.row(rows) = Eigen::Map<const Eigen::RowVectorXd>(physical(t, y), n);
    result.quadrature.row(rows) = quad_now.transpose();
    ++rows;
    if (options.progress) options.progress(t);
    if (system.range_check) {
      out_of_range = system.range_check(Instant{t, piece_mid}, result.x.row(rows - 1).transpose());
      if (!out_of_range.empty()) {
        result.failure_time = t;
        result.message = "at t = " + fmt(t) + ": " + out_of_range;
        return false;
      }
    }
    return true;
  };
  auto finish = [&](bool ok) {
    result.status = ok ? IntegrationStatus::Completed
                       : !out_of_range.empty() ? IntegrationStatus::OutOfRange : IntegrationStatus::Failed;
    result.t.conservativeResize(rows);
    result.x.conservativeResize(rows, n);
    result.quadrature.conservativeResize(rows, nq);
    return result;
  };

  result.t(0) = t0;
  result.x.row(0) = x0.transpose();
  rows = 1;
  if (system.range_check) {
    out_of_range = system.range_check(Instant{t0, t0}, x0);
    if (!out_of_range.empty()) {
      result.failure_time = t0;
      result.message = "at t = " + fmt(t0) + ": " + out_of_range;
      return finish(false);
    }
  }
  if (n_out == 1) return finish(true);

  // Piece boundaries: t0, the breakpoints strictly inside (t0, tend) sorted and deduplicated, tend.
  std::vector<double> bounds;
  bounds.reserve(breakpoints.size() + 2);
  bounds.push_back(t0);
  for (double b : breakpoints)
    if (b > t0 && b < tend) bounds.push_back(b);  // NaN compares false and is dropped
  bounds.push_back(tend);
  std::sort(bounds.begin() + 1, bounds.end() - 1);
  bounds.erase(std::unique(bounds.begin(), bounds.end()), bounds.end());

  const bool explicit_rk = options.method != IntegratorOptions::Method::Bdf &&
                           options.method != IntegratorOptions::Method::Adams;
  const std::unique_ptr<detail::PieceStepper> stepper =
      explicit_rk ? detail::runge_kutta_stepper(system, options) : detail::cvodes_stepper(system, options);
  double* y = stepper->state();
  Eigen::Map<Eigen::VectorXd> y_map(y, n);
  // x -> y for the piece starting at `start` (identity without a change of variables).
  auto enter = [&](const Instant& start, const Eigen::VectorXd& x) {
    piece_mid = start.piece_mid;
    if (!change.active()) {
      y_map = x;
      return true;
    }
    bool ok = false;
    std::string threw;
    try {
      ok = change.enter_piece(start, x, y_map) && y_map.allFinite();
    } catch (const std::exception& e) {
      threw = std::string("threw: ") + e.what();
    }
    if (!ok) {
      result.failure_time = start.t;
      result.message = "the change of integration variables failed at t = " + fmt(start.t) + ": " +
                       (threw.empty() ? detail::user_message(system, "right-hand side") : threw);
    }
    return ok;
  };
  auto statistics = [&]() {
    result.steps = stepper->steps();
    result.rhs_evaluations = stepper->rhs_evaluations();
  };
  const double first_mid = 0.5 * (bounds[0] + bounds[1]);
  if (!enter(Instant{t0, first_mid}, x0)) return finish(false);
  stepper->start(t0, first_mid);

  // Returns false (and fills the failure fields) when the stepper failed or the state went
  // non-finite; `at_stop`: the state is the one at the piece's end.
  // the work units each step charges to options.budget
  const long long work = system.step_work > 0 ? system.step_work : step_work(n, options.method);
  auto advance = [&](double tout, bool& at_stop) {
    // With a total budget, this call may take only what is left of it.
    long limit = options.max_steps;
    bool budget_binds = false;
    if (options.max_total_steps > 0) {
      const long left = options.max_total_steps - stepper->steps();
      budget_binds = left < options.max_steps;
      limit = std::min(options.max_steps, left);
    }
    const detail::PieceStepper::Outcome step = stepper->advance(tout, limit, budget_binds, options.budget.get(), work);
    at_stop = step.at_stop;
    if (!step.ok) {
      result.failure_time = step.reached;
      result.message = step.message;
      return false;
    }
    if (!Eigen::Map<const Eigen::VectorXd>(y, n).allFinite()) {
      result.failure_time = step.reached;
      result.message = std::string(stepper->name()) + " failed at t = " + fmt(step.reached) +
                       ": the state became non-finite";
      return false;
    }
    if (nq > 0) quad_now = Eigen::Map<const Eigen::VectorXd>(stepper->quadrature(), nq);
    return true;
  };

  std::size_t next = 1;  // output_times[0] = t0 is recorded from x0
  for (std::size_t k = 0; k + 1 < bounds.size(); ++k) {
    const double a = bounds[k];
    const double b = bounds[k + 1];
    if (roundoff_span(a, b)) {  // a roundoff-sized piece: the state is unchanged over it
      while (next < n_out && output_times[next] <= b)
        if (!record(output_times[next++], y)) return statistics(), finish(false);
      continue;
    }
    // The stepper started at t0; every later piece restarts from the current state, mapped
    // to this piece's variables when they change.
    const double mid = 0.5 * (a + b);
    if (a != t0) {
      if (change.active()) {
        const Eigen::VectorXd x_at_a = Eigen::Map<const Eigen::VectorXd>(physical(a, y), n);
        if (!enter(Instant{a, mid}, x_at_a)) return statistics(), finish(false);
      }
      stepper->restart(a, mid, quad_now.data());
    }
    stepper->stop_time(b);

    bool at_end = false;     // the stepper has returned the state at b
    bool stepped = false;    // it was called in this piece
    while (next < n_out && output_times[next] <= b) {
      const double tout = output_times[next];
      if (!at_end && !(!stepped && roundoff_span(a, tout))) {
        bool at_stop = false;
        const bool ok = advance(tout, at_stop);
        stepped = true;
        if (!ok) return statistics(), finish(false);
        at_end = at_stop || tout == b;
      }
      ++next;
      if (!record(tout, y)) return statistics(), finish(false);
    }
    if (!at_end) {
      bool at_stop = false;
      if (!advance(b, at_stop)) return statistics(), finish(false);
    }
  }
  statistics();
  return finish(true);
}

}  // namespace freeflex
