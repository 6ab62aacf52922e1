#pragma once
// One Ipopt solve of a collocation NLP from a starting point, in freeflex's terms: the
// adapter (trajopt/ipopt_adapter.cpp) keeps Ipopt's types to itself. Private to src/.
#include <limits>
#include <string>

#include <Eigen/Dense>

#include "freeflex/trajopt/collocation.hpp"
#include "freeflex/trajopt/solve.hpp"

namespace freeflex::detail {

/// Multipliers of the variables' lower and upper bounds (Ipopt's z_L and z_U).
struct BoundMultipliers {
  Eigen::VectorXd lower, upper;
};

/// What one Ipopt solve returned.
struct NlpSolve {
  TrajoptStatus status = TrajoptStatus::Failed;
  std::string message;  ///< Ipopt's status in words (and the first evaluation error)
  Eigen::VectorXd w;    ///< the last point (empty if Ipopt returned none)
  double objective = std::numeric_limits<double>::quiet_NaN();
  BoundMultipliers z;   ///< at the last point (empty if Ipopt returned none)
  int iterations = 0;
  std::string log;      ///< Ipopt's output, when options.keep_log or the derivative test asked for it
};

/// Solves `nlp` from `w0` with the options of TrajoptOptions (trajopt/solve.hpp says which
/// Ipopt options freeflex sets, constr_mult_init_max 0 among them); the derivative test
/// runs only with `check_derivatives`, and `warm` starts close to the central path
/// (mu_init 1e-6); `z0`, when given (with `warm`), are the bound multipliers to start
/// from (Ipopt's warm_start_init_point; the constraint multipliers start at zero as in
/// every solve). Throws std::invalid_argument for an Ipopt option Ipopt does not know or
/// rejects.
NlpSolve solve_nlp_ipopt(const CollocationNlp& nlp, const Eigen::VectorXd& w0, const TrajoptOptions& options,
                         bool check_derivatives, bool warm, const BoundMultipliers* z0 = nullptr);

/// Errors reported by Ipopt's derivative checker in its log; -1 if it printed no verdict.
int derivative_errors(const std::string& log);

}  // namespace freeflex::detail
