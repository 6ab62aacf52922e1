// ODE integration with SUNDIALS CVODES 6.x, cut into pieces at breakpoints
// (docs/theory.md section 8).
#include "freeflex/sim/integrator.hpp"

#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sim/fast_nvector.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

static_assert(sizeof(sunrealtype) == sizeof(double), "freeflex needs SUNDIALS built with double precision");

std::string fmt(double v) { return util::format_number(v, 12); }

/// Everything SUNDIALS allocates, freed in reverse order of creation on every path.
struct CvodeResources {
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  void* mem = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  SUNNonlinearSolver NLS = nullptr;

  CvodeResources() = default;
  CvodeResources(const CvodeResources&) = delete;
  CvodeResources& operator=(const CvodeResources&) = delete;
  ~CvodeResources() {
    if (mem) CVodeFree(&mem);  // first: it references the solvers and the context
    if (NLS) SUNNonlinSolFree(NLS);
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }
};

/// Passed to the C callbacks as user data.
struct CallbackData {
  const OdeSystem* system = nullptr;
  long dim = 0;
  double piece_mid = 0.0;
  std::string callback_error;  ///< why the rhs / Jacobian wrapper failed (first failure kept)
  bool failed = false;         ///< a callback failed unrecoverably: every later rhs call fails too
  std::string cvode_error;     ///< the last error message CVODE itself produced
  double rtol = 0.0;
  Eigen::VectorXd atol;        ///< per component
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

extern "C" void freeflex_cvode_err(int error_code, const char* module, const char* function, char* msg,
                                   void* user_data) {
  // Warnings (error_code > 0, e.g. "t + h = t") are dropped; errors are kept for the message.
  if (error_code >= 0) return;
  auto* data = static_cast<CallbackData*>(user_data);
  try {
    data->cvode_error = std::string(module ? module : "CVODE") + "::" + (function ? function : "?") + ": " +
                        (msg ? msg : "");
  } catch (...) {
    // out of memory while copying a message: nothing sensible to do, and nothing may escape
  }
}

std::string flag_name(long flag) {
  char* name = CVodeGetReturnFlagName(flag);  // malloc'ed by SUNDIALS
  if (!name) return "flag " + std::to_string(flag);
  std::string s(name);
  std::free(name);
  return s;
}

/// Setup calls must succeed; a failure here is an internal error, not a numerical one.
void check_setup(int flag, const char* call, const CallbackData& data) {
  if (flag == CV_SUCCESS) return;
  std::string msg = std::string("freeflex::integrate: ") + call + " failed with " + flag_name(flag);
  if (!data.cvode_error.empty()) msg += " (" + data.cvode_error + ")";
  throw std::runtime_error(msg);
}

template <class P>
P check_alloc(P p, const char* call) {
  if (!p) throw std::runtime_error(std::string("freeflex::integrate: ") + call + " failed (out of memory?)");
  return p;
}

std::string explain(int flag, const CallbackData& data, long max_steps) {
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
  std::string detail = !data.callback_error.empty() ? data.callback_error : data.cvode_error;
  if (!detail.empty()) why = why.empty() ? detail : why + ": " + detail;
  return why;
}

void validate(const OdeSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x0,
              const std::vector<double>& output_times, const IntegratorOptions& options) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("freeflex::integrate: " + what); };
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
  if (!(options.rtol > 0.0) || !std::isfinite(options.rtol))
    fail("expected finite rtol > 0, got " + fmt(options.rtol));
  if (!(options.atol > 0.0) || !std::isfinite(options.atol))
    fail("expected finite atol > 0, got " + fmt(options.atol));
  if (!(options.max_step >= 0.0) || !std::isfinite(options.max_step))
    fail("expected finite max_step >= 0 (0: no limit), got " + fmt(options.max_step));
  if (options.max_steps <= 0) fail("expected max_steps > 0, got " + std::to_string(options.max_steps));
}

}  // namespace

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

  IntegrationResult result;
  result.t.resize(static_cast<Eigen::Index>(n_out));
  result.x.resize(static_cast<Eigen::Index>(n_out), n);
  Eigen::Index rows = 0;
  Eigen::VectorXd x_scratch(n);
  double piece_mid = t0;  // of the piece whose variables y currently holds
  // y -> x under the current piece's variables.
  auto physical = [&](double t, const double* y) -> const double* {
    if (!change.active()) return y;
    change.to_x(Instant{t, piece_mid}, Eigen::Map<const Eigen::VectorXd>(y, n), x_scratch);
    return x_scratch.data();
  };
  auto record = [&](double t, const double* y) {
    result.t(rows) = t;
    result.x.row(rows) = Eigen::Map<const Eigen::RowVectorXd>(physical(t, y), n);
    ++rows;
    if (options.progress) options.progress(t);
  };
  auto finish = [&](bool ok) {
    result.ok = ok;
    result.t.conservativeResize(rows);
    result.x.conservativeResize(rows, n);
    return result;
  };

  result.t(0) = t0;
  result.x.row(0) = x0.transpose();
  rows = 1;
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

  CvodeResources cv;
  if (SUNContext_Create(nullptr, &cv.ctx) != 0 || !cv.ctx)
    throw std::runtime_error("freeflex::integrate: SUNContext_Create failed");
  cv.y = check_alloc(N_VNew_Serial(static_cast<sunindextype>(n), cv.ctx), "N_VNew_Serial");
  use_compiled_vector_kernels(cv.y);  // CVODES clones its work vectors from y: they inherit them
  double* y = N_VGetArrayPointer(cv.y);
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

  const bool bdf = options.method == IntegratorOptions::Method::Bdf;
  cv.mem = check_alloc(CVodeCreate(bdf ? CV_BDF : CV_ADAMS, cv.ctx), "CVodeCreate");
  check_setup(CVodeSetErrHandlerFn(cv.mem, freeflex_cvode_err, &data), "CVodeSetErrHandlerFn", data);
  check_setup(CVodeInit(cv.mem, freeflex_cvode_rhs, t0, cv.y), "CVodeInit", data);
  check_setup(CVodeSetUserData(cv.mem, &data), "CVodeSetUserData", data);  // also what the weights receive
  data.rtol = options.rtol;
  data.atol = change.active() && change.atol_scale.size() == n ? Eigen::VectorXd(options.atol * change.atol_scale)
                                                                : Eigen::VectorXd::Constant(n, options.atol);
  check_setup(CVodeWFtolerances(cv.mem, freeflex_error_weights), "CVodeWFtolerances", data);
  check_setup(CVodeSetMaxNumSteps(cv.mem, options.max_steps), "CVodeSetMaxNumSteps", data);
  if (options.max_step > 0.0) check_setup(CVodeSetMaxStep(cv.mem, options.max_step), "CVodeSetMaxStep", data);
  if (options.max_order > 0) check_setup(CVodeSetMaxOrd(cv.mem, options.max_order), "CVodeSetMaxOrd", data);
  if (bdf) {
    cv.A = check_alloc(SUNDenseMatrix(static_cast<sunindextype>(n), static_cast<sunindextype>(n), cv.ctx),
                       "SUNDenseMatrix");
    cv.LS = check_alloc(SUNLinSol_Dense(cv.y, cv.A, cv.ctx), "SUNLinSol_Dense");
    check_setup(CVodeSetLinearSolver(cv.mem, cv.LS, cv.A), "CVodeSetLinearSolver", data);
    if (system.jacobian && !change.active())
      check_setup(CVodeSetJacFn(cv.mem, freeflex_cvode_jac), "CVodeSetJacFn", data);
  } else {
    cv.NLS = check_alloc(SUNNonlinSol_FixedPoint(cv.y, 0, cv.ctx), "SUNNonlinSol_FixedPoint");
    check_setup(CVodeSetNonlinearSolver(cv.mem, cv.NLS), "CVodeSetNonlinearSolver", data);
  }

  // Adds the counters of the current piece (CVodeInit / CVodeReInit reset them).
  auto add_statistics = [&]() {
    long nst = 0, nfe = 0, nfe_ls = 0;
    check_setup(CVodeGetNumSteps(cv.mem, &nst), "CVodeGetNumSteps", data);
    check_setup(CVodeGetNumRhsEvals(cv.mem, &nfe), "CVodeGetNumRhsEvals", data);
    if (bdf) check_setup(CVodeGetNumLinRhsEvals(cv.mem, &nfe_ls), "CVodeGetNumLinRhsEvals", data);
    result.steps += nst;
    result.rhs_evaluations += nfe + nfe_ls;
  };

  // Returns false (and fills the failure fields) when CVode failed or the state went non-finite.
  auto advance = [&](double tout, int& flag) {
    sunrealtype tret = tout;
    flag = CVode(cv.mem, tout, cv.y, &tret, CV_NORMAL);
    if (flag < 0) {
      result.failure_time = tret;
      result.message = "CVODE failed at t = " + fmt(tret) + ": " + flag_name(flag);
      const std::string why = explain(flag, data, options.max_steps);
      if (!why.empty()) result.message += " (" + why + ")";
      return false;
    }
    if (!Eigen::Map<const Eigen::VectorXd>(y, n).allFinite()) {
      result.failure_time = tret;
      result.message = "CVODE failed at t = " + fmt(tret) + ": the state became non-finite";
      return false;
    }
    return true;
  };

  std::size_t next = 1;  // output_times[0] = t0 is recorded from x0
  for (std::size_t k = 0; k + 1 < bounds.size(); ++k) {
    const double a = bounds[k];
    const double b = bounds[k + 1];
    if (roundoff_span(a, b)) {  // a roundoff-sized piece: the state is unchanged over it
      while (next < n_out && output_times[next] <= b) record(output_times[next++], y);
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
      check_setup(CVodeReInit(cv.mem, a, cv.y), "CVodeReInit", data);
    }
    check_setup(CVodeSetStopTime(cv.mem, b), "CVodeSetStopTime", data);

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
      record(tout, y);
      ++next;
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
