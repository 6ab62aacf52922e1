#pragma once
// The first-order model of a bang-bang rotation, as the switch-time design and the
// residual check both evaluate it: the targeted modes, the rigid end state of a set of
// interval durations, and the first-order simulation of a design. Private to src/.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/control/switch_time.hpp"

namespace freeflex::detail {

/// `v` with 10 significant digits, for messages.
std::string fmt10(double v);

/// Throws std::invalid_argument unless `actuator` is a torque element at o and o is the
/// mass centre.
void validate_actuator(const FlexibleBody& body, int actuator, const std::string& where);

/// The first `modes` elastic modes of the rest model (eq. 4.1, at attitude theta) that the
/// torque excites: frequencies, mass-normalized shapes, participation vᵀ g.
struct TargetModes {
  Eigen::VectorXd omega, participation;
  Eigen::MatrixXd shapes;  // N x k
  Eigen::MatrixXd M0;      // 𝕄0 at theta
};

TargetModes target_modes(const FlexibleBody& body, int actuator, double theta, int modes, const std::string& where);

/// Switch times of interval durations Δ (their partial sums), and T = Σ Δ.
std::vector<double> switches_of(const std::vector<double>& durations, double& T);

/// Rigid end state θ0(T), θ0'(T) of durations Δ (signs +, −, ...) and their gradients.
void rigid_end(const std::vector<double>& D, double a, double& theta, double& rate, std::vector<double>* dtheta,
               std::vector<double>* drate);

/// A bang-bang design as the stages evaluate it.
struct Problem {
  const FlexibleBody* body = nullptr;
  int actuator = 0, k = 0;
  double I_o = 0.0, tau = 0.0, a = 0.0, dtheta = 0.0;
  double scale = 1.0;  // sqrt(I_o) θ'* : modal constraints divided by it
  TargetModes modes;
  double rtol = 1e-11, atol = 1e-14;
  long max_total_steps = 0;  ///< of each simulation (0: no limit)
  // Work: caps on the simulations (a count P.simulations may reach) and on all their
  // steps together (0: no cap); reaching one sets budget_spent and no simulation runs.
  int max_simulations = 0;
  long max_steps_all = 0;
  std::shared_ptr<WorkBudget> budget;  ///< every simulation's (SwitchTimeOptions::budget)
  int simulations = 0;
  long steps = 0, longest = 0;  // all steps, and those of the longest simulation
  long closed_form_evaluations = 0;
  bool budget_spent = false;
  std::function<void(int)> progress;  // SwitchTimeOptions::progress
  std::string last_error;
};

/// First-order simulation of a design: x1(T) (and the peak rate θ0' if asked); false,
/// with P.last_error, when it fails or the work budget is spent (P.budget_spent: no
/// simulation runs after that).
bool simulate(Problem& P, const std::vector<double>& D, Eigen::VectorXd& x1_end, double* peak_rate = nullptr);

/// Modal constraints [ω η, η'] / scale of the first-order state at T.
void modal_from_state(const Problem& P, const Eigen::VectorXd& x1, double* c);

}  // namespace freeflex::detail
