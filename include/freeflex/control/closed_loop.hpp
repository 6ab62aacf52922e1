#pragma once
// Closed-loop simulation of a TV-LQR law (tvlqr.hpp) designed on the first-order model:
//  (a) on the first-order model itself: x1' = A x1 + B u1 + g,
//  (b) on the full nonlinear model (eq. 6.2): the controller sees the full state as
//      perturbation coordinates x1 = [R − R0(t), θ − θ0(t), q, R' − R0', θ' − θ0', q'].
// In both, actuator k receives u0_k(t) + u1_k with u1 = −K(t) x1 + u_ff(t), saturated at
// |u| <= limit_k; loads follow their time profiles as in an open-loop run. Times in s,
// commands in N or N m.
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/control/tvlqr.hpp"
#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/model/loads.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex {

/// Nominal actuator commands u0(t): a callback that writes one entry per input of the
/// first-order model into the buffer it is handed.
using ActuatorCommandFunction = std::function<void(const Instant&, Eigen::Ref<Eigen::VectorXd>)>;

/// The element commands of the nominal motion: every load's profile plus u0 on the
/// actuators (element indices `inputs`), for FirstOrderModel's nominal commands. An empty
/// u0 means zero. Throws std::invalid_argument if an input is not an element of the
/// excitation (index outside [0, profiles.size())) or an actuator also has a profile.
CommandFunction nominal_element_commands(const Excitation& loads, const std::vector<int>& inputs,
                                         ActuatorCommandFunction u0 = {});

/// BDF: an LQR closed loop has fast real poles (−8.6e3 1/s on the paper beam at NOA 6
/// with energy weights) that would hold Adams to tiny steps.
inline IntegratorOptions closed_loop_integrator() {
  IntegratorOptions o;
  o.method = IntegratorOptions::Method::Bdf;
  return o;
}

/// How the closed loop on the first-order model is integrated (docs/theory.md, "The
/// closed loop on the first-order model"). The full model's is always CVODES's.
enum class ClosedLoopMethod {
  /// CVODES with ClosedLoopOptions::integrator (BDF, error control to rtol and atol).
  Cvodes,
  /// 5-stage Gauss-Legendre collocation (order 10) on the linear system x1' = (A − B K) x1
  /// + B c + g, with fixed steps: `gauss_steps` per interval between consecutive gain grid
  /// times, output times and breakpoints (so no step straddles a kink of K(t) or a jump),
  /// one linear solve per step, a step across a saturation switch halved until it is
  /// 2^-40 of its length. No error control: the accuracy is set by gauss_steps (on
  /// designs/suppress_slew.toml, 8 steps per 5 ms interval: 6.8e-14 from a long-double
  /// reference, BDF at rtol 1e-14 2.4e-12). A-stable, not L-stable: fast real closed-loop
  /// poles need |λ| h of a few (the moment example's −8.6e3 1/s at a 10 ms gain grid:
  /// 16 steps 7.4e-10, 8 steps 2.4e-7 in the rates after saturation switches).
  Gauss,
};

struct ClosedLoopOptions {
  IntegratorOptions integrator = closed_loop_integrator();  ///< CVODES settings (max_total_steps and progress serve Gauss too)
  ClosedLoopMethod first_order_method = ClosedLoopMethod::Cvodes;  ///< of simulate_closed_loop_first_order
  int gauss_steps = 8;               ///< Gauss steps per interval, in [1, 1000]
  double t_begin = 0.0;              ///< [s]; with t_end <= t_begin: the law's [t0, tf]
  double t_end = 0.0;
  double output_step_s = 0.005;      ///< [s], > 0
  Eigen::VectorXd limits;            ///< |u0 + u1| <= limits(k) [N or N m], each > 0; empty: no limits
  Eigen::VectorXd x1_initial;        ///< perturbation at t_begin (size 2N); empty: zero
  std::vector<double> breakpoints;   ///< extra breakpoints (the nominal's and loads' are added)
};

/// Throws std::invalid_argument naming the first setting out of range (sizes are checked
/// against the model by the simulations); the defaults are valid.
void validate(const ClosedLoopOptions& options);

struct ClosedLoopResult {
  IntegrationStatus status = IntegrationStatus::Failed;
  std::string message;
  bool ok() const { return status == IntegrationStatus::Completed; }
  Eigen::VectorXd t;        ///< output times reached
  Eigen::MatrixXd z;        ///< totals [Rx, Ry, θ, q], one row per time
  Eigen::MatrixXd z_dot;
  Eigen::MatrixXd commands; ///< applied actuator commands u0 + u1 after saturation (T x m)
  Eigen::MatrixXd demanded; ///< before saturation
  /// Fraction of output times at which some actuator is saturated, and per actuator.
  double saturated_fraction = 0.0;
  Eigen::VectorXd saturated_fraction_per_actuator;
  double peak_command = 0.0;  ///< max |applied command| over actuators and times
  double peak_demand = 0.0;   ///< max |demanded command|
  long rhs_evaluations = 0;  ///< CVODES: right-hand sides; Gauss: evaluations of A, B, g, K
  long steps = 0;            ///< CVODES or Gauss steps
  double wall_time_s = 0.0;
};

/// (a) The law on the first-order model it was designed on. The model's nominal commands
/// must already contain u0 on the actuators (see nominal_element_commands); u0 is needed
/// here only to saturate the total command. Throws std::invalid_argument for sizes that
/// do not match the model (law gains, limits, x1_initial) or bad times.
ClosedLoopResult simulate_closed_loop_first_order(const FirstOrderModel& model, const TvlqrResult& law,
                                                  const ActuatorCommandFunction& u0,
                                                  const ClosedLoopOptions& options);

/// (b) The law on the full nonlinear model. `model` supplies the body, the nominal motion
/// and the actuators (its inputs); `loads` the load profiles of every element (actuators
/// must have none). The initial state is the nominal state at t_begin plus x1_initial.
ClosedLoopResult simulate_closed_loop_full(const FirstOrderModel& model, const Excitation& loads,
                                           const ActuatorCommandFunction& u0, const TvlqrResult& law,
                                           const ClosedLoopOptions& options);

template <>
struct EnumNames<ClosedLoopMethod> {
  static constexpr const char* what = "closed-loop method";
  static constexpr std::array<std::pair<ClosedLoopMethod, const char*>, 2> names{
      {{ClosedLoopMethod::Cvodes, "cvodes"}, {ClosedLoopMethod::Gauss, "gauss"}}};
};

}  // namespace freeflex
