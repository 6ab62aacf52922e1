// ODE integration with SUNDIALS CVODES 6.x, cut into pieces at breakpoints
// (docs/theory.md section 8).
#include "freeflex/sim/integrator.hpp"

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sim/cvodes.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

std::string fmt(double v) { return util::format_number(v, 12); }

/// Passed to the C callbacks as user data.
struct CallbackData {
  const OdeSystem* system = nullptr;
  long dim = 0;
  double piece_mid = 0.0;
  std::string callback_error;  ///< why the rhs / Jacobian wrapper failed (first failure kept)
  bool failed = false;         ///< a callback failed unrecoverably: every later rhs call fails too
  double rtol = 0.0;
  Eigen::VectorXd atol;        ///< per component
  Eigen::VectorXd x_quad;      ///< the physical state for the quadrature integrand (a change of variables)
};

/// CVODES's error weights w_i = 1 / (rtol |y_i| + atol_i), as its own CVodeSVtolerances
/// computes them (same operations, same bits), in one compiled loop instead of the four
/// vector calls of Debian's unoptimized library: ~3% of a full-model run.
extern "C" int freeflex_error_weights(N_Vector y, N_Vector w, void* user_data) {
  const auto* data = static_cast<const CallbackData*>(user_data);
  const double* yd = N_VGetArrayPointer(y);
  double* wd = N_VGetArrayPointer(w);
  const double* atol = data->atol.data();
  for (long i = 0; i < data->dim; ++i) {
    const double denominator = data->rtol * std::fabs(yd[i]) + atol[i];
    if (!(denominator > 0.0)) return -1;  // CVODES's own test: a weight must be finite and positive
    wd[i] = 1.0 / denominator;
  }
  return 0;
}

std::string user_message(const OdeSystem& system, const char* what) {
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

void fail_callback(CallbackData& data, std::string msg) {
  data.failed = true;
  if (data.callback_error.empty()) data.callback_error = std::move(msg);
}

extern "C" int freeflex_cvode_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto* data = static_cast<CallbackData*>(user_data);
  // SUNDIALS 6.4's fixed-point solver (Adams) treats a negative return from the rhs like a
  // convergence failure and retries with a smaller step; it only ends after repeated
  // failures within one step, so once failed the rhs keeps failing without calling back.
  if (data->failed) return -1;
  try {
    Eigen::Map<const Eigen::VectorXd> x(N_VGetArrayPointer(y), data->dim);
    Eigen::Map<Eigen::VectorXd> xdot(N_VGetArrayPointer(ydot), data->dim);
    const Instant at{t, data->piece_mid};
    if (!data->system->rhs(at, x, xdot)) {
      fail_callback(*data,
                 "right-hand side failed at t = " + fmt(t) + ": " + user_message(*data->system, "right-hand side"));
      return -1;
    }
    if (!xdot.allFinite()) {
      fail_callback(*data, "right-hand side returned a non-finite derivative at t = " + fmt(t));
      return -1;
    }
    return 0;
  } catch (const std::exception& e) {
    fail_callback(*data, "right-hand side threw at t = " + fmt(t) + ": " + e.what());
  } catch (...) {
    fail_callback(*data, "right-hand side threw an unknown exception at t = " + fmt(t));
  }
  return -1;
}

extern "C" int freeflex_cvode_quad(sunrealtype t, N_Vector y, N_Vector yQdot, void* user_data) {
  auto* data = static_cast<CallbackData*>(user_data);
  if (data->failed) return -1;
  try {
    const OdeSystem& sys = *data->system;
    Eigen::Map<const Eigen::VectorXd> yv(N_VGetArrayPointer(y), data->dim);
    Eigen::Map<Eigen::VectorXd> out(N_VGetArrayPointer(yQdot), sys.quadrature_dim);
    const Instant at{t, data->piece_mid};
    bool ok = false;
    if (sys.variables.active()) {
      sys.variables.to_x(at, yv, data->x_quad);
      ok = sys.quadrature(at, data->x_quad, out);
    } else {
      ok = sys.quadrature(at, yv, out);
    }
    if (ok && out.allFinite()) return 0;
    fail_callback(*data, "the quadrature integrand failed or was not finite at t = " + fmt(t));
  } catch (const std::exception& e) {
    fail_callback(*data, "the quadrature integrand threw at t = " + fmt(t) + ": " + e.what());
  } catch (...) {
    fail_callback(*data, "the quadrature integrand threw an unknown exception at t = " + fmt(t));
  }
  return -1;
}

extern "C" int freeflex_cvode_jac(sunrealtype t, N_Vector y, N_Vector /*fy*/, SUNMatrix J, void* user_data,
                                  N_Vector /*tmp1*/, N_Vector /*tmp2*/, N_Vector /*tmp3*/) {
  auto* data = static_cast<CallbackData*>(user_data);
  try {
    Eigen::Map<const Eigen::VectorXd> x(N_VGetArrayPointer(y), data->dim);
    // SUNDIALS dense matrices are column-major with leading dimension = rows, as Eigen's.
    Eigen::Map<Eigen::MatrixXd> jac(SUNDenseMatrix_Data(J), SUNDenseMatrix_Rows(J), SUNDenseMatrix_Columns(J));
    jac.setZero();
    const Instant at{t, data->piece_mid};
    if (!data->system->jacobian(at, x, jac)) {
      fail_callback(*data,
                 "Jacobian failed at t = " + fmt(t) + ": " + user_message(*data->system, "Jacobian"));
      return -1;
    }
    if (!jac.allFinite()) {
      fail_callback(*data, "Jacobian has non-finite entries at t = " + fmt(t));
      return -1;
    }
    return 0;
  } catch (const std::exception& e) {
    fail_callback(*data, "Jacobian threw at t = " + fmt(t) + ": " + e.what());
  } catch (...) {
    fail_callback(*data, "Jacobian threw an unknown exception at t = " + fmt(t));
  }
  return -1;
}

std::string explain(int flag, const CallbackData& data, const std::string& cvode_error, long max_steps) {
  std::string why;
  switch (flag) {
    case CV_TOO_MUCH_WORK:
      why = "max_steps = " + std::to_string(max_steps) +
            " internal steps taken in this piece before reaching the next output time; the problem may be stiff "
            "(use BDF) or max_steps too small";
      break;
    case CV_TOO_MUCH_ACC:
      why = "the requested accuracy cannot be reached in double precision; raise rtol/atol";
      break;
    case CV_ERR_FAILURE:
      why = "the local error test failed repeatedly or with |h| = hmin; the solution may be singular or the "
            "right-hand side discontinuous at a time that is not a breakpoint";
      break;
    case CV_CONV_FAILURE:
      if (data.failed) {  // fixed-point solver: an unrecoverable rhs failure ends up here
        why = "the right-hand side failed unrecoverably";
        break;
      }
      why = "the nonlinear solver failed to converge repeatedly or with |h| = hmin; the problem may be stiff "
            "(Adams) or the Jacobian wrong";
      break;
    case CV_RHSFUNC_FAIL:
      why = "the right-hand side failed unrecoverably";
      break;
    case CV_FIRST_RHSFUNC_ERR:
      why = "the right-hand side failed at the first call";
      break;
    case CV_REPTD_RHSFUNC_ERR:
      why = "the right-hand side failed repeatedly";
      break;
    case CV_UNREC_RHSFUNC_ERR:
      why = "the right-hand side failed and CVODE could not recover";
      break;
    case CV_LSETUP_FAIL:
      why = "the linear solver setup (Jacobian evaluation or LU factorization) failed";
      break;
    case CV_LSOLVE_FAIL:
      why = "the linear solve failed";
      break;
    default:
      break;
  }
  std::string detail = !data.callback_error.empty() ? data.callback_error : cvode_error;
  if (!detail.empty()) why = why.empty() ? detail : why + ": " + detail;
  return why;
}

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
     << " units (CVODES steps weighted by the size of what they integrate; README, the \"(limits)\" row) is spent";
  return os.str();
}

long long step_work(long dim, IntegratorOptions::Method method) {
  const long long N = std::max(1L, dim / 2);
  const long long w = std::max(N * N, 400LL);
  return method == IntegratorOptions::Method::Bdf ? 3 * w : w;
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

  CallbackData data;
  data.system = &system;
  data.dim = n;
  data.piece_mid = 0.5 * (bounds[0] + bounds[1]);

  const bool bdf = options.method == IntegratorOptions::Method::Bdf;
  cvodes::Integrator cv(n, bdf ? cvodes::Integrator::Method::Bdf : cvodes::Integrator::Method::Adams,
                        "freeflex::integrate");
  double* y = cv.state();
  Eigen::Map<Eigen::VectorXd> y_map(y, n);
  // x -> y for the piece starting at `start` (identity without a change of variables).
  auto enter = [&](const Instant& start, const Eigen::VectorXd& x) {
    piece_mid = start.piece_mid;
    if (!change.active()) {
      y_map = x;
      return true;
    }
    bool ok = false;
    try {
      ok = change.enter_piece(start, x, y_map) && y_map.allFinite();
    } catch (const std::exception& e) {
      data.callback_error = std::string("threw: ") + e.what();
    }
    if (!ok) {
      result.failure_time = start.t;
      result.message = "the change of integration variables failed at t = " + fmt(start.t) + ": " +
                       (data.callback_error.empty() ? user_message(system, "right-hand side") : data.callback_error);
    }
    return ok;
  };
  if (!enter(Instant{t0, data.piece_mid}, x0)) return finish(false);

  cv.init(freeflex_cvode_rhs, t0, &data);  // the user data is also what the weights receive
  if (nq > 0) {
    data.x_quad.resize(n);
    cv.quadrature(freeflex_cvode_quad, quad_now.data(), nq);
  }
  data.rtol = options.rtol;
  data.atol = change.active() && change.atol_scale.size() == n ? Eigen::VectorXd(options.atol * change.atol_scale)
                                                                : Eigen::VectorXd::Constant(n, options.atol);
  cv.weight_function(freeflex_error_weights);
  cv.max_num_steps(options.max_steps);
  if (options.max_step > 0.0) cv.max_step(options.max_step);
  if (options.max_order > 0) cv.max_order(options.max_order);
  if (bdf)
    cv.dense_newton(system.jacobian && !change.active() ? freeflex_cvode_jac : nullptr);
  else
    cv.fixed_point();

  // Adds the counters of the current piece (CVodeInit / CVodeReInit reset them).
  auto add_statistics = [&]() {
    const cvodes::Counters c = cv.counters();
    result.steps += c.steps;
    result.rhs_evaluations += c.rhs_evaluations + c.linear_rhs_evaluations;
  };

  const long long work = system.step_work > 0 ? system.step_work : step_work(n, options.method);
  // Returns false (and fills the failure fields) when CVode failed or the state went non-finite.
  auto advance = [&](double tout, int& flag) {
    // With a total step count or a shared work budget, this call may take only what is left.
    long limit = options.max_steps;
    bool total_binds = false;
    if (options.max_total_steps > 0) {
      const long left = options.max_total_steps - result.steps - cv.counters().steps;
      total_binds = left < options.max_steps;
      limit = std::max(1L, std::min(options.max_steps, left));
    }
    bool by_budget = false;
    const cvodes::Integrator::Advance step = cv.advance(tout, limit, options.budget.get(), work, by_budget);
    flag = step.flag;
    const double tret = step.reached;
    if (flag < 0) {
      result.failure_time = tret;
      if (flag == CV_TOO_MUCH_WORK && by_budget) {
        result.message = "stopped at t = " + fmt(tret) + ": " + options.budget->spent_message();
        return false;
      }
      result.message = "CVODE failed at t = " + fmt(tret) + ": " + cvodes::Integrator::flag_name(flag);
      const std::string why =
          flag == CV_TOO_MUCH_WORK && total_binds
              ? "the integration's step budget, max_total_steps = " + std::to_string(options.max_total_steps) +
                    ", is spent; the simulated span needs more work than it allows"
              : explain(flag, data, cv.last_error(), options.max_steps);
      if (!why.empty()) result.message += " (" + why + ")";
      return false;
    }
    if (!Eigen::Map<const Eigen::VectorXd>(y, n).allFinite()) {
      result.failure_time = tret;
      result.message = "CVODE failed at t = " + fmt(tret) + ": the state became non-finite";
      return false;
    }
    if (nq > 0) quad_now = Eigen::Map<const Eigen::VectorXd>(cv.quadrature_values(), nq);
    return true;
  };

  std::size_t next = 1;  // output_times[0] = t0 is recorded from x0
  for (std::size_t k = 0; k + 1 < bounds.size(); ++k) {
    const double a = bounds[k];
    const double b = bounds[k + 1];
    if (roundoff_span(a, b)) {  // a roundoff-sized piece: the state is unchanged over it
      while (next < n_out && output_times[next] <= b)
        if (!record(output_times[next++], y)) return finish(false);
      continue;
    }
    // CVodeInit was done at t0; every later piece restarts from the current state, mapped
    // to this piece's variables when they change.
    data.piece_mid = 0.5 * (a + b);
    if (a != t0) {
      if (change.active()) {
        const Eigen::VectorXd x_at_a = Eigen::Map<const Eigen::VectorXd>(physical(a, y), n);
        if (!enter(Instant{a, data.piece_mid}, x_at_a)) return finish(false);
      }
      cv.reinit(a);
      if (nq > 0) cv.quadrature_reinit(quad_now.data());
    }
    cv.stop_time(b);

    bool at_end = false;     // CVODE has returned the state at b
    bool stepped = false;    // CVode was called in this piece
    while (next < n_out && output_times[next] <= b) {
      const double tout = output_times[next];
      if (!at_end && !(!stepped && roundoff_span(a, tout))) {
        int flag = 0;
        const bool ok = advance(tout, flag);
        stepped = true;
        if (!ok) {
          add_statistics();
          return finish(false);
        }
        at_end = flag == CV_TSTOP_RETURN || tout == b;
      }
      ++next;
      if (!record(tout, y)) {
        add_statistics();
        return finish(false);
      }
    }
    if (!at_end) {
      int flag = 0;
      if (!advance(b, flag)) {
        add_statistics();
        return finish(false);
      }
    }
    add_statistics();
  }
  return finish(true);
}

}  // namespace freeflex
