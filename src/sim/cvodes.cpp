// The shared CVODES wrapper (sim/cvodes.hpp): ownership, setup checks, error messages.
#include "sim/cvodes.hpp"

#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <utility>

#include "sim/fast_nvector.hpp"

namespace freeflex::cvodes {

void record_error(Integrator& integrator, const char* module, const char* function, const char* msg) {
  integrator.last_error_ =
      std::string(module ? module : "CVODES") + "::" + (function ? function : "?") + ": " + (msg ? msg : "");
}

namespace {

extern "C" void freeflex_cvodes_error(int error_code, const char* module, const char* function, char* msg,
                                      void* eh_data) {
  // Warnings (error_code > 0, e.g. "t + h = t") are dropped; errors are kept for the message.
  if (error_code >= 0) return;
  try {
    record_error(*static_cast<Integrator*>(eh_data), module, function, msg);
  } catch (...) {
    // out of memory while copying a message: nothing sensible to do, and nothing may escape
  }
}

template <class P>
P allocated(P p, const std::string& who, const char* call) {
  if (!p) throw std::runtime_error(who + ": " + call + " failed (out of memory?)");
  return p;
}

}  // namespace

Integrator::Integrator(long dim, Method method, std::string who) : dim_(dim), who_(std::move(who)) {
  if (SUNContext_Create(nullptr, &ctx_) != 0 || !ctx_) throw std::runtime_error(who_ + ": SUNContext_Create failed");
  y_ = allocated(N_VNew_Serial(static_cast<sunindextype>(dim), ctx_), who_, "N_VNew_Serial");
  use_compiled_vector_kernels(y_);  // CVODES clones its work vectors from y: they inherit them
  mem_ = allocated(CVodeCreate(method == Method::Bdf ? CV_BDF : CV_ADAMS, ctx_), who_, "CVodeCreate");
  check(CVodeSetErrHandlerFn(mem_, freeflex_cvodes_error, this), "CVodeSetErrHandlerFn");
}

Integrator::~Integrator() {
  if (mem_) CVodeFree(&mem_);  // first: it references the solvers and the context
  if (NLS_) SUNNonlinSolFree(NLS_);
  if (LS_) SUNLinSolFree(LS_);
  if (A_) SUNMatDestroy(A_);
  if (yQ_) N_VDestroy(yQ_);
  if (y_) N_VDestroy(y_);
  if (ctx_) SUNContext_Free(&ctx_);
}

double* Integrator::state() const { return N_VGetArrayPointer(y_); }

void Integrator::init(CVRhsFn rhs, double t0, void* user_data) {
  check(CVodeInit(mem_, rhs, t0, y_), "CVodeInit");
  check(CVodeSetUserData(mem_, user_data), "CVodeSetUserData");
}

void Integrator::scalar_tolerances(double rtol, double atol) {
  check(CVodeSStolerances(mem_, rtol, atol), "CVodeSStolerances");
}

void Integrator::weight_function(CVEwtFn weights) { check(CVodeWFtolerances(mem_, weights), "CVodeWFtolerances"); }

void Integrator::max_num_steps(long steps) { check(CVodeSetMaxNumSteps(mem_, steps), "CVodeSetMaxNumSteps"); }

void Integrator::max_step(double step) { check(CVodeSetMaxStep(mem_, step), "CVodeSetMaxStep"); }

void Integrator::max_order(int order) { check(CVodeSetMaxOrd(mem_, order), "CVodeSetMaxOrd"); }

void Integrator::dense_newton(CVLsJacFn jacobian) {
  const auto n = static_cast<sunindextype>(dim_);
  A_ = allocated(SUNDenseMatrix(n, n, ctx_), who_, "SUNDenseMatrix");
  LS_ = allocated(SUNLinSol_Dense(y_, A_, ctx_), who_, "SUNLinSol_Dense");
  check(CVodeSetLinearSolver(mem_, LS_, A_), "CVodeSetLinearSolver");
  if (jacobian) check(CVodeSetJacFn(mem_, jacobian), "CVodeSetJacFn");
}

void Integrator::fixed_point() {
  NLS_ = allocated(SUNNonlinSol_FixedPoint(y_, 0, ctx_), who_, "SUNNonlinSol_FixedPoint");
  check(CVodeSetNonlinearSolver(mem_, NLS_), "CVodeSetNonlinearSolver");
}

void Integrator::matrix_embedded(SUNLinearSolver solver) {
  LS_ = allocated(solver, who_, "SUNLinSolNewEmpty");
  check(CVodeSetLinearSolver(mem_, LS_, nullptr), "CVodeSetLinearSolver");
}

void Integrator::gmres(int max_krylov, CVLsPrecSetupFn setup, CVLsPrecSolveFn solve, CVLsJacTimesSetupFn jtsetup,
                       CVLsJacTimesVecFn jtimes) {
  LS_ = allocated(SUNLinSol_SPGMR(y_, SUN_PREC_LEFT, max_krylov, ctx_), who_, "SUNLinSol_SPGMR");
  check(CVodeSetLinearSolver(mem_, LS_, nullptr), "CVodeSetLinearSolver");
  check(CVodeSetPreconditioner(mem_, setup, solve), "CVodeSetPreconditioner");
  check(CVodeSetJacTimes(mem_, jtsetup, jtimes), "CVodeSetJacTimes");
}

void Integrator::reinit(double t) { check(CVodeReInit(mem_, t, y_), "CVodeReInit"); }

void Integrator::quadrature(CVQuadRhsFn fQ, const double* initial, long dim) {
  yQ_ = allocated(N_VNew_Serial(static_cast<sunindextype>(dim), ctx_), who_, "N_VNew_Serial");
  std::copy(initial, initial + dim, N_VGetArrayPointer(yQ_));
  check(CVodeQuadInit(mem_, fQ, yQ_), "CVodeQuadInit");
  check(CVodeSetQuadErrCon(mem_, SUNFALSE), "CVodeSetQuadErrCon");
}

void Integrator::quadrature_reinit(const double* values) {
  std::copy(values, values + N_VGetLength(yQ_), N_VGetArrayPointer(yQ_));
  check(CVodeQuadReInit(mem_, yQ_), "CVodeQuadReInit");
}

const double* Integrator::quadrature_values() {
  sunrealtype t = 0.0;
  check(CVodeGetQuad(mem_, &t, yQ_), "CVodeGetQuad");
  return N_VGetArrayPointer(yQ_);
}

void Integrator::stop_time(double t) { check(CVodeSetStopTime(mem_, t), "CVodeSetStopTime"); }

Integrator::Advance Integrator::advance(double tout) {
  sunrealtype reached = tout;
  const int flag = CVode(mem_, tout, y_, &reached, CV_NORMAL);
  return {flag, reached};
}

Integrator::Advance Integrator::advance(double tout, long max_steps, WorkBudget* budget, long long step_work,
                                        bool& by_budget) {
  by_budget = false;
  long allowed = max_steps;
  if (budget) {
    const long left = budget->steps_left(step_work);
    if (left < allowed) {
      allowed = left;
      by_budget = true;
    }
  }
  if (allowed < 1) {  // CVODE takes a limit <= 0 for its default of 500 steps
    sunrealtype now = 0.0;
    check(CVodeGetCurrentTime(mem_, &now), "CVodeGetCurrentTime");
    if (tout > now) {  // (time runs forward in every integration here)
      budget->mark_exhausted();
      return {CV_TOO_MUCH_WORK, now};
    }
    allowed = 1;  // tout lies within the last step: CVODE interpolates, no step is taken
  }
  max_num_steps(allowed);
  long before = 0, after = 0;
  check(CVodeGetNumSteps(mem_, &before), "CVodeGetNumSteps");
  const Advance a = advance(tout);
  if (budget) {
    check(CVodeGetNumSteps(mem_, &after), "CVodeGetNumSteps");
    budget->charge(static_cast<long long>(after - before) * step_work);
    if (a.flag == CV_TOO_MUCH_WORK && by_budget) budget->mark_exhausted();
  }
  return a;
}

Counters Integrator::counters() const {
  Counters c;
  check(CVodeGetNumSteps(mem_, &c.steps), "CVodeGetNumSteps");
  check(CVodeGetNumRhsEvals(mem_, &c.rhs_evaluations), "CVodeGetNumRhsEvals");
  if (LS_) {
    check(CVodeGetNumLinRhsEvals(mem_, &c.linear_rhs_evaluations), "CVodeGetNumLinRhsEvals");
    check(CVodeGetNumLinIters(mem_, &c.linear_iterations), "CVodeGetNumLinIters");
  }
  return c;
}

std::string Integrator::flag_name(int flag) {
  char* name = CVodeGetReturnFlagName(flag);  // malloc'ed by SUNDIALS
  if (!name) return "flag " + std::to_string(flag);
  std::string s(name);
  std::free(name);
  return s;
}

void Integrator::check(int flag, const char* call) const {
  if (flag == CV_SUCCESS) return;
  std::string msg = who_ + ": " + call + " failed with " + flag_name(flag);
  if (!last_error_.empty()) msg += " (" + last_error_ + ")";
  throw std::runtime_error(msg);
}

}  // namespace freeflex::cvodes
