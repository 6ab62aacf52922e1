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
// Integration (why it is done this way): P, s, c are integrated together by CVODES BDF
// in reversed time τ = tf − t (where the Riccati flow is stable), with the upper triangle
// of P as state (n(n+1)/2 entries: symmetry exact by construction, and half the vector
// work of the full square; it cut the NOA = 6 benchmark from 60 to 49 ms). The Newton
// systems (I − γJ) of BDF are solved exactly for a closed loop A_cl = A − S P frozen at
// the last refresh (every 50 steps, after a convergence failure, at each breakpoint), or
// on request by GMRES preconditioned with that solve: the P block is the shifted
// Lyapunov equation (A_clᵀ − I/2γ) Z + Z (A_cl − I/2γ) = −R/γ and the s, c blocks follow
// by block-triangular solves (O(n³) instead of the O(n⁶) dense LU of an
// n(n+1)/2-dimensional Jacobian: 18 states → 171 + 19 unknowns, 46 → 1081 + 47 for
// NOA = 20). A_cl is block-diagonalized at each refresh (then a solve is four n x n
// products and closed-form 2x2 blocks) unless its eigenvector basis is ill-conditioned
// (κ > modal_max_condition, e.g. P ≈ 0 with the free body's rigid double integrators),
// when its real Schur form is used (control/lyapunov_solvers.hpp in src/). BDF rather
// than Adams because the LQR closed loop is stiff (a real pole at −8.6e3 1/s on the
// paper beam at NOA = 6). The step count (~1000 per second of time-varying model at
// NOA = 6) is set by the lightly damped closed-loop modes (−7 ± 308i 1/s), which BDF
// must resolve; it hardly depends on rtol, so the cost is per step: with the vector
// kernels compiled here (the installed SUNDIALS is unoptimized), the block-diagonal
// Newton solves and AVX2 products (detail::small_gemm), the NOA = 6 benchmark went from
// 47 to 15.5 ms (~16 µs per step, about a third of it in the model's A(t), B(t), g(t),
// 600 of whose ~1600 evaluations are at the output grid) and NOA = 20 from 3.5 to 1.0 s.
// The model is evaluated at Instant{t, piece_mid} of the pieces between the breakpoints
// of the nominal motion (plus any given), and the integrator restarts at each of them.
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
  double rtol = 1e-8;          ///< CVODES relative tolerance, > 0
  double atol = 1e-10;         ///< absolute tolerance, relative to σ (see above), > 0
  long max_steps = 200000;     ///< per piece, > 0
  std::vector<double> breakpoints;  ///< extra breakpoints (e.g. load profile times) [s]
  bool store_riccati = false;       ///< keep P at every grid time (n² doubles each)
  /// Newton systems of BDF: Lyapunov = the exact solve for the closed loop frozen at the
  /// last setup (modified Newton, one O(n³) solve per iteration); Gmres = GMRES with that
  /// solve as preconditioner and exact Jacobian products (more work per iteration, kept as
  /// a cross-check).
  enum class NewtonSolver { Lyapunov, Gmres } newton_solver = NewtonSolver::Lyapunov;
  /// The frozen closed loop is block-diagonalized (~3x cheaper solves) when its
  /// eigenvector basis has κ₁ <= this, else brought to real Schur form. 0: always the
  /// Schur form.
  double modal_max_condition = 1e6;
  /// Optional: called with tf - t each time the backward sweep stores a grid time t
  /// (for progress reports on long solves); must not throw.
  std::function<void(double)> progress;
  /// Optional: the work budget the sweep is charged to (a study's, shared with its
  /// simulations), n³ units a step for n states (riccati_step_work); spending it ends the
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

  long steps = 0;
  long rhs_evaluations = 0;
  long linear_iterations = 0;
  long preconditioner_setups = 0;
  long modal_setups = 0;  ///< of those, how many used the block-diagonal form
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
struct EnumNames<TvlqrOptions::NewtonSolver> {
  static constexpr const char* what = "Newton solver";
  static constexpr std::array<std::pair<TvlqrOptions::NewtonSolver, const char*>, 2> names{
      {{TvlqrOptions::NewtonSolver::Lyapunov, "lyapunov"}, {TvlqrOptions::NewtonSolver::Gmres, "gmres"}}};
};

}  // namespace freeflex
