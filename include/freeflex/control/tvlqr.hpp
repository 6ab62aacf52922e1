#pragma once
// Finite-horizon time-varying LQR (TV-LQR) on the first-order model x1' = A x1 + B u1 + g
// (eq. 7.3) over [t0, tf], minimizing
//   J = ∫ (x1ᵀ Q x1 + u1ᵀ R u1) dt + x1(tf)ᵀ Qf x1(tf).
// The value function is V(t, x) = xᵀ P x + 2 sᵀ x + c with, backwards from tf,
//   −P' = Aᵀ P + P A − P S P + Q,    P(tf) = Qf,  S = B R⁻¹ Bᵀ     (Riccati)
//   −s' = (A − B K)ᵀ s + P g,        s(tf) = 0                      (known forcing)
//   −c' = 2 sᵀ g − sᵀ S s,           c(tf) = 0
// and the optimal law u1 = −K x1 + u_ff with K = R⁻¹ Bᵀ P, u_ff = −R⁻¹ Bᵀ s.
//
// Integration (why it is done this way; docs/theory.md §12 and docs/benchmarks.md give
// the measurements). P, s, c are integrated together in reversed time τ = tf − t, where
// the Riccati flow is stable, piece by piece between the breakpoints of the model (the
// nominal motion's, plus any given); the model is evaluated at Instant{t, piece_mid}.
// The flow is stiff (a real closed-loop pole at −8.6e3 1/s on the paper beam at NOA = 6,
// −3e5 at NOA = 20) and its linearization, X ↦ A_clᵀ X + X A_cl, has the lightly damped
// closed-loop modes' sums λi + λj (−14 ± 616i 1/s at NOA = 6, up to ±7740i at NOA = 20).
//
// Method::Auto (the default) takes the exponential sweep from 24 states up (NOA >= 9 for a
// beam with three rigid coordinates), BDF below, where BDF's cheaper steps win.
//
// Method::Exponential: exponential collocation. On each step the closed
// loop A_cl = A − S P is frozen at the predicted midpoint and block-diagonalized
// (ModalLyapunovSolver, src/control/lyapunov_solvers.hpp); in that basis the linear part
// of the flow, stiff and oscillatory alike, is integrated exactly by φ-functions, and
// what it misses (the model's change over the step, the quadratic term) is interpolated
// at three Gauss nodes found by fixed-point iteration (src/control/riccati_exponential.hpp).
// The step is then set by how fast those remainders vary, not by the oscillation: 75
// steps on the NOA = 20 benchmark instead of BDF's 11 904. For the first-order model the
// sweep runs in its rotating frame (the displacement and velocity of o turned by θ0(t)):
// the model's A is inertial there and changes with θ0, in the frame only with θ0' and
// θ0''. A step whose frozen loop has no well-conditioned block-diagonal form (κ₁ >
// 100 modal_max_condition, e.g. P ≈ 0 with the free body's rigid double integrators) is
// taken by BDF. The local error of a step (rtol, atol as below) is estimated from the
// defect of the remainders at its end; the law at the grid times inside a step comes
// from the same formulas.
//
// Method::Bdf: CVODES BDF on the upper triangle of P (n(n+1)/2 entries), s and c, its
// Newton systems (I − γJ) solved exactly for a closed loop frozen at the last refresh
// (every 50 steps, after a convergence failure, at each breakpoint): the P block is the
// shifted Lyapunov equation (A_clᵀ − I/2γ) Z + Z (A_cl − I/2γ) = −R/γ, the s and c blocks
// follow by block-triangular solves, in the block-diagonal form of the frozen loop or, if
// its eigenvector basis is ill-conditioned, its real Schur form; or on request by GMRES
// preconditioned with that solve. BDF of order 3 to 5 is unstable for the lightly damped
// modes' sums unless h·ω ≲ 0.6, so its step (~1 ms at NOA = 6, 80 µs at NOA = 20) is set
// by the fastest of them whatever rtol is.
//
// K(t) and u_ff(t) are stored on a grid (t0, t0 + h, ..., tf, and every breakpoint) and
// interpolated linearly; both are continuous in t (B depends on θ0, not on θ0''), so a
// breakpoint needs one value. P is scaled by σ = max(|Qf|_max, |Q|_max) while integrated,
// so `atol` is relative to the largest weight.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/control/lqr.hpp"
#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/enum_names.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex {

/// A(t), B(t), g(t) of x' = A x + B u + g at an instant (sizes n x n, n x m, n).
using StateSpaceFunction = std::function<StateSpace(const Instant&)>;

/// A linear time-varying system: what the TV-LQR needs of a model.
struct LtvSystem {
  int state_size = 0;
  int input_size = 0;
  StateSpaceFunction state_space;
  std::vector<double> breakpoints;  ///< where A, B or g may jump
};

/// The first-order model as an LtvSystem (breakpoints of its nominal motion). The model
/// must outlive the result.
LtvSystem ltv_system(const FirstOrderModel& model);

/// Settings of the TV-LQR solve; the problem (system, horizon, weights) is given to
/// solve_tvlqr as arguments.
struct TvlqrOptions {
  /// Terminal weight (n x n, symmetric PSD); empty: the CARE solution of the model at tf
  /// (on its controllable subspace, see CareOptions::restrict_to_controllable).
  std::optional<Eigen::MatrixXd> Qf;
  double grid_step_s = 0.005;  ///< spacing of the stored gains [s], > 0
  /// Exponential: exponential collocation in the frozen closed loop's modal basis (BDF for
  /// a step without one); Bdf: CVODES BDF throughout (the method before issue 19); Auto:
  /// Exponential for state_size >= kAutoExponentialStates, else Bdf. See above.
  enum class Method { Auto, Exponential, Bdf } method = Method::Auto;
  /// Where Auto switches: on the moment example the exponential sweep takes ~100 steps
  /// whatever the NOA, BDF ~1000 per second of maneuver at NOA = 6 growing as the highest
  /// closed-loop frequency (11 904 at NOA = 20), and an exponential step costs ~12 BDF
  /// steps; measured (instructions) BDF 13% cheaper at NOA = 8 (22 states), the exponential
  /// sweep 23% cheaper at NOA = 10 (26 states) and 8x at NOA = 20.
  static constexpr int kAutoExponentialStates = 24;
  double rtol = 1e-8;          ///< relative tolerance of a step's local error, > 0
  double atol = 1e-10;         ///< absolute tolerance, relative to σ (see above), > 0
  long max_steps = 200000;     ///< > 0: BDF steps per CVODE call (between stored grid times); exponential steps per piece
  std::vector<double> breakpoints;  ///< extra breakpoints (e.g. load profile times) [s]
  bool store_riccati = false;       ///< keep P at every grid time (n² doubles each)
  /// Newton systems of BDF (Method::Bdf and the exponential method's BDF steps):
  /// Lyapunov = the exact solve for the closed loop frozen at the
  /// last setup (modified Newton, one O(n³) solve per iteration); Gmres = GMRES with that
  /// solve as preconditioner and exact Jacobian products (more work per iteration, kept as
  /// a cross-check).
  enum class NewtonSolver { Lyapunov, Gmres } newton_solver = NewtonSolver::Lyapunov;
  /// The frozen closed loop is block-diagonalized when its eigenvector basis has κ₁ <=
  /// this (BDF's Newton solves; else they use its real Schur form) or <= 100 times this
  /// (an exponential step; else that step is taken by BDF). 0: never block-diagonalized
  /// (the exponential method then runs BDF throughout).
  double modal_max_condition = 1e6;
  /// Optional: called with tf - t each time the backward sweep stores a grid time t
  /// (for progress reports on long solves); must not throw.
  std::function<void(double)> progress;
  /// Optional: the work budget the sweep is charged to (a study's, shared with its
  /// simulations), n³ units a BDF step for n states (riccati_step_work), 16 n³ an
  /// exponential one; spending it ends the
  /// solve as IntegrationFailed with the time reached.
  std::shared_ptr<WorkBudget> budget;
};

/// Work units of one step of the Riccati sweep of an n-state system: n³ (its products
/// and Newton solves are n x n; measured 2.5 to 5.5 ns of CPU per unit from NOA 6 to 40).
long long riccati_step_work(int n);

/// Throws std::invalid_argument naming the first setting out of range; the defaults are
/// valid. (Qf is checked against the system by solve_tvlqr.)
void validate(const TvlqrOptions& options);

struct TvlqrResult {
  enum class Status { Solved, TerminalCareFailed, IntegrationFailed };
  Status status = Status::IntegrationFailed;
  std::string message;
  bool ok() const { return status == Status::Solved; }

  std::vector<double> t;                 ///< grid, ascending from t0 to tf
  std::vector<Eigen::MatrixXd> K;        ///< m x n gain at each grid time
  Eigen::MatrixXd feedforward;           ///< one row per grid time: u_ff = −R⁻¹ Bᵀ s
  std::vector<Eigen::MatrixXd> P;        ///< only with store_riccati
  Eigen::MatrixXd P0;                    ///< P(t0)
  Eigen::VectorXd s0;                    ///< s(t0)
  double c0 = 0.0;                       ///< c(t0)
  Eigen::MatrixXd Qf;                    ///< the terminal weight used
  std::optional<CareResult> terminal_care;  ///< when Qf was defaulted

  /// The sweep that ran: Exponential or Bdf (Auto resolved by the state size).
  TvlqrOptions::Method method = TvlqrOptions::Method::Bdf;
  long steps = 0;                  ///< accepted steps (exponential and BDF)
  long rhs_evaluations = 0;
  long linear_iterations = 0;      ///< GMRES iterations (NewtonSolver::Gmres)
  long preconditioner_setups = 0;  ///< closed-loop factorizations (per exponential step, per BDF refresh)
  long modal_setups = 0;           ///< of those, how many gave the block-diagonal form
  long rejected_steps = 0;         ///< exponential steps retried smaller (error or fixed-point test)
  long fixed_point_iterations = 0; ///< of the exponential steps' stage values
  long fallback_steps = 0;         ///< exponential steps taken by BDF (no block-diagonal form)
  double wall_time_s = 0.0;

  /// Linear interpolation on the grid, held constant outside [t0, tf].
  Eigen::MatrixXd gain(double time) const;
  Eigen::VectorXd feedforward_at(double time) const;
  /// u1 = −K(t) x1 + u_ff(t).
  Eigen::VectorXd control(double time, const Eigen::Ref<const Eigen::VectorXd>& x1) const;
  /// Optimal cost from x1 at t0: x1ᵀ P0 x1 + 2 s0ᵀ x1 + c0.
  double predicted_cost(const Eigen::Ref<const Eigen::VectorXd>& x1) const;
};

/// TV-LQR on any LTV system over [t0, tf] [s] with state weight Q (n x n, symmetric
/// PSD) and input weight R (m x m, symmetric PD). Throws std::invalid_argument (before
/// any work) for tf <= t0, non-finite times, weight sizes, Q or Qf not PSD, R not PD, or
/// options out of range. Numerical failure (terminal CARE, CVODES) is reported in the
/// result.
TvlqrResult solve_tvlqr(const LtvSystem& system, double t0, double tf, const Eigen::MatrixXd& Q,
                        const Eigen::MatrixXd& R, const TvlqrOptions& options = {});

/// TV-LQR on the first-order model. Additionally requires t0 >= nominal().t_begin() and
/// tf >= nominal().t_end(): the horizon must cover the whole nominal maneuver.
TvlqrResult solve_tvlqr(const FirstOrderModel& model, double t0, double tf, const Eigen::MatrixXd& Q,
                        const Eigen::MatrixXd& R, const TvlqrOptions& options = {});

template <>
struct EnumNames<TvlqrResult::Status> {
  static constexpr const char* what = "TV-LQR status";
  static constexpr std::array<std::pair<TvlqrResult::Status, const char*>, 3> names{
      {{TvlqrResult::Status::Solved, "solved"},
       {TvlqrResult::Status::TerminalCareFailed, "terminal_care_failed"},
       {TvlqrResult::Status::IntegrationFailed, "integration_failed"}}};
};

template <>
struct EnumNames<TvlqrOptions::Method> {
  static constexpr const char* what = "TV-LQR method";
  static constexpr std::array<std::pair<TvlqrOptions::Method, const char*>, 3> names{
      {{TvlqrOptions::Method::Auto, "auto"},
       {TvlqrOptions::Method::Exponential, "exponential"},
       {TvlqrOptions::Method::Bdf, "bdf"}}};
};

template <>
struct EnumNames<TvlqrOptions::NewtonSolver> {
  static constexpr const char* what = "Newton solver";
  static constexpr std::array<std::pair<TvlqrOptions::NewtonSolver, const char*>, 2> names{
      {{TvlqrOptions::NewtonSolver::Lyapunov, "lyapunov"}, {TvlqrOptions::NewtonSolver::Gmres, "gmres"}}};
};

}  // namespace freeflex
