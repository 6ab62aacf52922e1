#pragma once
// ODE integration with SUNDIALS CVODES or freeflex's own explicit Runge-Kutta pair
// (docs/theory.md section 8). The interval is cut at every load discontinuity
// ("breakpoint"); the integrator is re-initialized exactly there, so no step straddles a jump. Inside one piece the right-hand side is smooth.
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/enum_names.hpp"
#include "freeflex/model/instant.hpp"  // Instant: time plus the piece it belongs to
#include "freeflex/validation.hpp"

namespace freeflex {

/// An optional change of the variables CVODE integrates (docs/theory.md section 8): the
/// caller's state x and the integrated y have the same size. At the start of every piece
/// `enter_piece` maps x to y and may fix constants of that piece; `to_x` maps y back at
/// any time of the current piece. With a change set, OdeSystem::rhs gives y' = f(t, y).
struct VariableChange {
  std::function<bool(const Instant& start, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> y)>
      enter_piece;
  std::function<void(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> x)>
      to_x;
  /// Per component of y, multiplies IntegratorOptions::atol (empty: 1 for every component).
  Eigen::VectorXd atol_scale;
  bool active() const { return static_cast<bool>(enter_piece); }
};

/// x' = f(t, x). `rhs` and `jacobian` are callbacks: they write into the buffer they are
/// handed. `rhs` must not throw; it returns false to report a failure (the message is then
/// taken from `last_error`, if set). CVODES ends the run at the first failure; the explicit
/// pairs end it at a failure at an accepted state and reject a step one of whose trial
/// states fails (its stages, its new point, its interpolant's stages: the step is retried
/// shorter, so `rhs` may be called again after returning false).
struct OdeSystem {
  int dim = 0;
  std::function<bool(const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> xdot)>
      rhs;
  /// Optional dense Jacobian df/dx (dim x dim); without it CVODE uses difference quotients.
  std::function<bool(const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::MatrixXd> J)>
      jacobian;
  std::function<std::string()> last_error;
  /// Integrate other variables than x (identity when not set). `jacobian` is then
  /// ignored: CVODE's difference quotients serve BDF.
  VariableChange variables;
  /// Optional integrals along the solution, ∫ integrand(t, x) dt from the first output
  /// time (work done by loads, say): `quadrature_dim` entries, integrated with the
  /// states' own steps and outside their error test, so the states come out the same with
  /// or without them. A callback like rhs; false reports a failure.
  int quadrature_dim = 0;
  std::function<bool(const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> integrand)>
      quadrature;
  /// Optional: called at every output time with the state recorded there; a non-empty
  /// answer (why the state is outside the model's range) ends the integration at that
  /// time with IntegrationStatus::OutOfRange. Must not throw.
  std::function<std::string(const Instant&, const Eigen::Ref<const Eigen::VectorXd>& x)> range_check;
  /// Work units one step costs, charged to IntegratorOptions::budget; 0: step_work(dim,
  /// method), right for a model of dim / 2 coordinates. A system whose right-hand side
  /// costs more per state (matrix equations) says so here.
  long long step_work = 0;
};

/// A budget of integration work shared by every integration of a study (README, design
/// files, the "(limits)" row): each CVODES step charges its system's work units
/// (step_work). Spending it ends the integration in progress as a failure whose message
/// gives the time reached and names the budget; every later integration charged to it
/// stops before its first step. Integrations on several threads may share one.
class WorkBudget {
 public:
  /// `units` > 0; `owner` names it in messages ("the [simulation] study").
  WorkBudget(long long units, std::string owner);
  long long total() const { return total_; }
  long long spent() const { return spent_.load(); }
  long long left() const;
  /// Whole steps of `step_work` units that are left (0 when not one).
  long steps_left(long long step_work) const;
  void charge(long long units);
  /// An integration stopped because the budget was spent.
  bool exhausted() const { return exhausted_.load(); }
  void mark_exhausted() { exhausted_ = true; }
  const std::string& owner() const { return owner_; }
  /// "the [simulation] study's work budget (2e10 units: CVODES steps weighted by ...) is spent"
  std::string spent_message() const;

 private:
  long long total_;
  std::string owner_;
  std::atomic<long long> spent_{0};
  std::atomic<bool> exhausted_{false};
};

struct IntegratorOptions {
  double rtol = 1e-8;   ///< relative tolerance, > 0
  double atol = 1e-10;  ///< absolute tolerance, > 0 (same for every component)
  /// Adams suits the lightly damped oscillations here (fewer steps, no numerical damping
  /// of energy); BDF suits stiff cases (many functions, heavy damping). Dop853 (Dormand
  /// and Prince's 8(5,3) pair) and Verner98 (Verner's 9(8) pair) are freeflex's own
  /// explicit Runge-Kutta methods, not CVODES: cheaper than Adams at equal error when tight
  /// errors are wanted on a nonstiff problem (docs/theory.md section 8); they ignore
  /// `max_order` and the Jacobian.
  enum class Method { Bdf, Adams, Dop853, Verner98 } method = Method::Adams;
  double max_step = 0.0;       ///< 0: no limit [s]
  long max_steps = 1000000;    ///< per output interval (one CVode call); exceeding it is a failure
  /// Steps of the whole integration (every piece and output interval; accepted steps,
  /// for every method); 0: no limit.
  /// Spending it is a failure whose message gives the time reached (a bound on this
  /// integration alone; a study's integrations share `budget` instead).
  long max_total_steps = 0;
  int max_order = 0;           ///< 0: CVODE's default (BDF 5, Adams 12)
  /// Optional: called with each output time once the state there is recorded (for
  /// progress reports on long runs); must not throw.
  std::function<void(double t)> progress;
  /// Optional: the work budget this integration is charged to (shared with the other
  /// integrations of a study); spending it is a failure like max_total_steps.
  std::shared_ptr<WorkBudget> budget;
};

/// Work units of one CVODES step of an OdeSystem of `dim` states: max(N², 400) for
/// N = dim / 2 (a model's coordinates: the right-hand side's products and solves are
/// N x N), three times that with BDF (its Newton iterations and difference-quotient
/// Jacobians). Measured 1.4 to 6 ns of CPU per unit (README, the "(limits)" row).
long long step_work(long dim, IntegratorOptions::Method method);

/// Every setting out of range ("rtol = -1, expected a finite value > 0"); empty when valid.
std::vector<FieldProblem> problems(const IntegratorOptions& options);
/// Throws std::invalid_argument listing problems(options); the defaults are valid.
void validate(const IntegratorOptions& options);

/// The outcome of an integration, shared by the simulations built on it.
enum class IntegrationStatus {
  Completed,   ///< every output time was reached
  Failed,      ///< the integrator or the right-hand side failed; the message says why and when
  OutOfRange,  ///< the state left the model's range (OdeSystem::range_check); why and when in the message
};

struct IntegrationResult {
  IntegrationStatus status = IntegrationStatus::Failed;
  std::string message;        ///< the integrator's reason when not ok()
  bool ok() const { return status == IntegrationStatus::Completed; }
  double failure_time = 0.0;  ///< time reached when it failed
  Eigen::VectorXd t;          ///< output times actually reached
  Eigen::MatrixXd x;          ///< one row per output time
  Eigen::MatrixXd quadrature; ///< the OdeSystem's integrals at each output time (quadrature_dim columns)
  long rhs_evaluations = 0;   ///< right-hand side calls (incl. CVODE's Jacobian DQ, the dense output's stages)
  long steps = 0;
};

/// Spans shorter than this (seconds) are not integrated: CVODE takes a stop time so close
/// to t for one behind it (the product of two such spans underflows), and no load acting
/// for that long (at most 1e12 N by the design limits) moves anything.
inline constexpr double kMinSpan_s = 1e-100;

/// True when [a, b] (a <= b) cannot be integrated and need not be: within a few ulps of its
/// ends (CVODE's CV_TOO_CLOSE; the state changes by round-off only) or shorter than
/// kMinSpan_s. integrate() does not step over such a piece, and simulations merge a load
/// breakpoint that close to another into it.
bool roundoff_span(double a, double b);

/// Integrates from x0 at output_times.front() and records x at each output time
/// (ascending, at least one). `breakpoints` (any order, any count; those outside the
/// span are ignored) split the span into pieces. Throws std::invalid_argument for bad
/// arguments (sizes, non-ascending times, tolerances <= 0); numerical failure is
/// reported in the result with the time reached.
IntegrationResult integrate(const OdeSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x0,
                            const std::vector<double>& output_times, const std::vector<double>& breakpoints,
                            const IntegratorOptions& options);

template <>
struct EnumNames<IntegratorOptions::Method> {
  static constexpr const char* what = "integration method";
  static constexpr std::array<std::pair<IntegratorOptions::Method, const char*>, 4> names{
      {{IntegratorOptions::Method::Bdf, "bdf"},
       {IntegratorOptions::Method::Adams, "adams"},
       {IntegratorOptions::Method::Dop853, "dop853"},
       {IntegratorOptions::Method::Verner98, "verner98"}}};
};

template <>
struct EnumNames<IntegrationStatus> {
  static constexpr const char* what = "integration status";
  static constexpr std::array<std::pair<IntegrationStatus, const char*>, 3> names{
      {{IntegrationStatus::Completed, "completed"},
       {IntegrationStatus::Failed, "failed"},
       {IntegrationStatus::OutOfRange, "out_of_range"}}};
};

}  // namespace freeflex
