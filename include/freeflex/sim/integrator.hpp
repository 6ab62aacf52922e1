#pragma once
// ODE integration with SUNDIALS CVODES (docs/theory.md section 8). The interval is cut
// at every load discontinuity ("breakpoint"); the integrator is re-initialized exactly
// there, so no step straddles a jump. Inside one piece the right-hand side is smooth.
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/model/instant.hpp"  // Instant: time plus the piece it belongs to

namespace freeflex {

/// x' = f(t, x). `rhs` must not throw; it returns false to report a failure (the message
/// is then taken from `last_error`, if set).
struct OdeSystem {
  int dim = 0;
  std::function<bool(const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> xdot)>
      rhs;
  /// Optional dense Jacobian df/dx (dim x dim); without it CVODE uses difference quotients.
  std::function<bool(const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::MatrixXd> J)>
      jacobian;
  std::function<std::string()> last_error;
};

struct IntegratorOptions {
  double rtol = 1e-8;   ///< relative tolerance, > 0
  double atol = 1e-10;  ///< absolute tolerance, > 0 (same for every component)
  /// Adams suits the lightly damped oscillations here (fewer steps, no numerical damping
  /// of energy); BDF suits stiff cases (many functions, heavy damping).
  enum class Method { Bdf, Adams } method = Method::Adams;
  double max_step = 0.0;       ///< 0: no limit [s]
  long max_steps = 1000000;    ///< per piece; exceeding it is a failure
  int max_order = 0;           ///< 0: CVODE's default (BDF 5, Adams 12)
};

struct IntegrationResult {
  bool ok = false;
  std::string message;        ///< CVODE's reason when !ok
  double failure_time = 0.0;  ///< time reached when it failed
  Eigen::VectorXd t;          ///< output times actually reached
  Eigen::MatrixXd x;          ///< one row per output time
  long rhs_evaluations = 0;   ///< right-hand side calls (CVODE's count, incl. Jacobian DQ)
  long steps = 0;
};

/// Integrates from x0 at output_times.front() and records x at each output time
/// (ascending, at least one). `breakpoints` (any order, any count; those outside the
/// span are ignored) split the span into pieces. Throws std::invalid_argument for bad
/// arguments (sizes, non-ascending times, tolerances <= 0); numerical failure is
/// reported in the result with the time reached.
IntegrationResult integrate(const OdeSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x0,
                            const std::vector<double>& output_times, const std::vector<double>& breakpoints,
                            const IntegratorOptions& options);

}  // namespace freeflex
