#pragma once
// The one wrapper of SUNDIALS CVODES 6.x that every solver in freeflex goes through (the
// piecewise integrator of sim/integrator.cpp and the backward Riccati sweep of
// control/tvlqr_sweep.cpp): it owns the context, the state vector, the integrator memory
// and its solvers, frees them in the right order on every path, checks every setup call,
// keeps CVODE's last error message and names return flags. Private to src/.
#include <cvodes/cvodes.h>
#include <cvodes/cvodes_ls.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>
#include <sundials/sundials_nvector.h>

#include <string>

#include "freeflex/sim/integrator.hpp"  // WorkBudget

namespace freeflex::cvodes {

static_assert(sizeof(sunrealtype) == sizeof(double), "freeflex needs SUNDIALS built with double precision");

/// CVODE's counters since the last init or reinit.
struct Counters {
  long steps = 0;
  long rhs_evaluations = 0;
  long linear_rhs_evaluations = 0;  ///< difference-quotient Jacobian evaluations (dense BDF); 0 otherwise
  long linear_iterations = 0;       ///< Krylov iterations (GMRES); 0 otherwise
};

class Integrator {
 public:
  enum class Method { Adams, Bdf };

  /// A state vector of `dim` entries whose vector operations are freeflex's compiled
  /// kernels (sim/fast_nvector.hpp), and the integrator memory. `who` starts the message
  /// of a failed setup call ("freeflex::integrate", "solve_tvlqr"). Throws
  /// std::runtime_error when SUNDIALS cannot allocate.
  Integrator(long dim, Method method, std::string who);
  ~Integrator();
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;

  long dim() const { return dim_; }
  SUNContext context() const { return ctx_; }
  double* state() const;  ///< the state vector's entries
  N_Vector vector() const { return y_; }
  void* memory() const { return mem_; }

  /// CVodeInit at t0 with the state's current entries; `user_data` reaches every callback.
  void init(CVRhsFn rhs, double t0, void* user_data);
  void scalar_tolerances(double rtol, double atol);
  /// The error weights come from `weights` instead of CVODE's tolerances.
  void weight_function(CVEwtFn weights);
  void max_num_steps(long steps);
  void max_step(double step);
  void max_order(int order);

  /// Newton iterations with a dense direct solver; `jacobian` null: difference quotients.
  void dense_newton(CVLsJacFn jacobian);
  /// Fixed-point (functional) iterations, for Adams on nonstiff problems.
  void fixed_point();
  /// Newton iterations whose linear systems `solver` answers by itself (matrix-embedded);
  /// the integrator takes ownership.
  void matrix_embedded(SUNLinearSolver solver);
  /// Newton iterations with GMRES, left-preconditioned, and Jacobian-vector products.
  void gmres(int max_krylov, CVLsPrecSetupFn setup, CVLsPrecSolveFn solve, CVLsJacTimesSetupFn jtsetup,
             CVLsJacTimesVecFn jtimes);

  /// Quadratures yQ' = fQ(t, y) of `dim` entries starting from `initial`, integrated
  /// with the states' own steps and kept out of their error test (CVODES's default): the
  /// states' solution is the same with or without them.
  void quadrature(CVQuadRhsFn fQ, const double* initial, long dim);
  /// Restarts the quadratures from `values` (after reinit).
  void quadrature_reinit(const double* values);
  /// The quadratures at the time CVODE last returned (CVodeGetQuad).
  const double* quadrature_values();

  /// Restarts at t from the state's current entries (counters restart too).
  void reinit(double t);
  void stop_time(double t);
  /// One CVode call in normal mode towards `tout`: CVODE's flag (< 0 failure) and the
  /// time reached.
  struct Advance {
    int flag;
    double reached;
  };
  Advance advance(double tout);
  /// One CVode call towards `tout` of at most `max_steps` (> 0) steps and of what `budget`
  /// (null: none) has left at `step_work` units a step, charged to it with the steps
  /// taken. With not one step left it does not call CVode: CV_TOO_MUCH_WORK at the current
  /// time. `by_budget` says whether the budget bound this call (a CV_TOO_MUCH_WORK is then
  /// its doing, and the budget is marked exhausted).
  Advance advance(double tout, long max_steps, WorkBudget* budget, long long step_work, bool& by_budget);
  Counters counters() const;

  /// CVODE's last error message ("CVODES::CVode: ..."), empty if none.
  const std::string& last_error() const { return last_error_; }
  /// CVODE's name of a return flag ("CV_TOO_MUCH_WORK").
  static std::string flag_name(int flag);
  /// Throws std::runtime_error "<who>: <call> failed with <flag name> (<CVODE's message>)"
  /// unless `flag` is success: a failed setup call is an internal error, not a numerical one.
  void check(int flag, const char* call) const;

 private:
  friend void record_error(Integrator& integrator, const char* module, const char* function, const char* msg);
  long dim_;
  std::string who_;
  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector yQ_ = nullptr;  ///< quadratures, if any
  void* mem_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver LS_ = nullptr;
  SUNNonlinearSolver NLS_ = nullptr;
  std::string last_error_;
};

}  // namespace freeflex::cvodes
