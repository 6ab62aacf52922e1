#pragma once
// One smooth piece of the time line at a time: the interface through which integrate()
// (sim/integrator.cpp) drives CVODES (sim/integrator_cvodes.cpp) or freeflex's explicit
// Runge-Kutta pairs (sim/runge_kutta.cpp). The driver owns pieces, output times, the
// change of variables, range checks and progress; a stepper only advances. Private to src/.
#include <memory>
#include <string>

#include "freeflex/sim/integrator.hpp"

namespace freeflex::detail {

class PieceStepper {
 public:
  virtual ~PieceStepper() = default;
  /// The integrated state y (OdeSystem::dim entries). The driver writes a piece's initial
  /// state here before start() or restart(); after advance() it holds y at the time reached.
  virtual double* state() = 0;
  /// The quadratures at the time last reached (OdeSystem::quadrature_dim entries).
  virtual const double* quadrature() = 0;
  /// Starts at t0 from state(), quadratures from zero; rhs calls carry `piece_mid`.
  virtual void start(double t0, double piece_mid) = 0;
  /// Restarts at t from state() and the quadratures `quad`, for the piece around `piece_mid`.
  virtual void restart(double t, double piece_mid, const double* quad) = 0;
  /// No step goes beyond b (the end of the current piece).
  virtual void stop_time(double b) = 0;

  struct Outcome {
    bool ok = true;
    bool at_stop = false;   ///< the state is the one at the stop time
    double reached = 0.0;   ///< time of state()
    std::string message;    ///< why it failed, with the time
  };
  /// Integrates to tout (not beyond the stop time) in at most `max_steps` steps;
  /// `budget_binds`: that limit is what is left of IntegratorOptions::max_total_steps.
  /// Each step charges `step_work` units to `budget` (null: none); with too few left it
  /// stops where it is, fails naming the budget, and marks it exhausted.
  virtual Outcome advance(double tout, long max_steps, bool budget_binds, WorkBudget* budget, long long step_work) = 0;

  virtual long steps() const = 0;            ///< since start(), every piece
  virtual long rhs_evaluations() const = 0;  ///< since start(), every piece
  virtual const char* name() const = 0;      ///< "CVODE", "DOP853", ...
};

/// CVODES with Adams or BDF, as IntegratorOptions ask (sim/integrator_cvodes.cpp).
std::unique_ptr<PieceStepper> cvodes_stepper(const OdeSystem& system, const IntegratorOptions& options);
/// An explicit embedded Runge-Kutta pair with dense output (sim/runge_kutta.cpp).
std::unique_ptr<PieceStepper> runge_kutta_stepper(const OdeSystem& system, const IntegratorOptions& options);

/// The user's message for a failed callback, or "<what> reported a failure".
std::string user_message(const OdeSystem& system, const char* what);

}  // namespace freeflex::detail
