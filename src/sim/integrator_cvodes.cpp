// CVODES behind the piece stepper of sim/stepper.hpp: its C callbacks (the model's
// right-hand side, quadratures, Jacobian and freeflex's error weights) and its return
// flags explained (docs/theory.md section 8).
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <string>
#include <utility>

#include "sim/cvodes.hpp"
#include "sim/stepper.hpp"
#include "util/finite.hpp"
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
                 "right-hand side failed at t = " + fmt(t) + ": " + detail::user_message(*data->system, "right-hand side"));
      return -1;
    }
    if (!util::all_finite(xdot)) {
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
                 "Jacobian failed at t = " + fmt(t) + ": " + detail::user_message(*data->system, "Jacobian"));
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

class CvodesStepper final : public detail::PieceStepper {
 public:
  CvodesStepper(const OdeSystem& system, const IntegratorOptions& options)
      : system_(system),
        options_(options),
        cv_(system.dim,
            options.method == IntegratorOptions::Method::Bdf ? cvodes::Integrator::Method::Bdf
                                                              : cvodes::Integrator::Method::Adams,
            "freeflex::integrate") {
    data_.system = &system;
    data_.dim = system.dim;
  }

  double* state() override { return cv_.state(); }
  const double* quadrature() override { return cv_.quadrature_values(); }

  void start(double t0, double piece_mid) override {
    const long n = system_.dim;
    const VariableChange& change = system_.variables;
    data_.piece_mid = piece_mid;
    cv_.init(freeflex_cvode_rhs, t0, &data_);  // the user data is also what the weights receive
    if (system_.quadrature_dim > 0) {
      data_.x_quad.resize(n);
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(system_.quadrature_dim);
      cv_.quadrature(freeflex_cvode_quad, zero.data(), system_.quadrature_dim);
    }
    data_.rtol = options_.rtol;
    data_.atol = change.active() && change.atol_scale.size() == n
                     ? Eigen::VectorXd(options_.atol * change.atol_scale)
                     : Eigen::VectorXd::Constant(n, options_.atol);
    cv_.weight_function(freeflex_error_weights);
    cv_.max_num_steps(options_.max_steps);
    if (options_.max_step > 0.0) cv_.max_step(options_.max_step);
    if (options_.max_order > 0) cv_.max_order(options_.max_order);
    if (options_.method == IntegratorOptions::Method::Bdf)
      cv_.dense_newton(system_.jacobian && !change.active() ? freeflex_cvode_jac : nullptr);
    else
      cv_.fixed_point();
  }

  void restart(double t, double piece_mid, const double* quad) override {
    add_counters();  // CVodeReInit resets them
    data_.piece_mid = piece_mid;
    cv_.reinit(t);
    if (system_.quadrature_dim > 0) cv_.quadrature_reinit(quad);
  }

  void stop_time(double b) override { cv_.stop_time(b); }

  Outcome advance(double tout, long max_steps, bool budget_binds, WorkBudget* budget, long long step_work) override {
    // this call may take only what is left of the integration's steps and of the budget
    bool by_budget = false;
    const cvodes::Integrator::Advance step =
        cv_.advance(tout, std::max(1L, max_steps), budget, step_work, by_budget);
    Outcome out;
    out.reached = step.reached;
    out.at_stop = step.flag == CV_TSTOP_RETURN;
    if (step.flag == CV_TOO_MUCH_WORK && by_budget) {
      out.ok = false;
      out.message = "stopped at t = " + fmt(step.reached) + ": " + budget->spent_message();
    } else if (step.flag < 0) {
      out.ok = false;
      out.message = "CVODE failed at t = " + fmt(step.reached) + ": " + cvodes::Integrator::flag_name(step.flag);
      const std::string why =
          step.flag == CV_TOO_MUCH_WORK && budget_binds
              ? "the integration's step budget, max_total_steps = " + std::to_string(options_.max_total_steps) +
                    ", is spent; the simulated span needs more work than it allows"
              : explain(step.flag, data_, cv_.last_error(), options_.max_steps);
      if (!why.empty()) out.message += " (" + why + ")";
    }
    return out;
  }

  long steps() const override { return steps_ + cv_.counters().steps; }
  long rhs_evaluations() const override {
    const cvodes::Counters c = cv_.counters();
    return rhs_ + c.rhs_evaluations + c.linear_rhs_evaluations;
  }
  const char* name() const override { return "CVODE"; }

 private:
  void add_counters() {
    const cvodes::Counters c = cv_.counters();
    steps_ += c.steps;
    rhs_ += c.rhs_evaluations + c.linear_rhs_evaluations;
  }

  const OdeSystem& system_;
  const IntegratorOptions& options_;
  CallbackData data_;
  cvodes::Integrator cv_;
  long steps_ = 0, rhs_ = 0;  ///< of the pieces before the current one
};

}  // namespace

std::unique_ptr<detail::PieceStepper> detail::cvodes_stepper(const OdeSystem& system,
                                                             const IntegratorOptions& options) {
  return std::make_unique<CvodesStepper>(system, options);
}

}  // namespace freeflex
