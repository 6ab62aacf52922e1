#pragma once
// Fixed-step Gauss-Legendre collocation for a linear time-varying system whose inputs
// saturate: the closed loop of a TV-LQR on the first-order model
// (ClosedLoopMethod::Gauss, docs/theory.md "The closed loop on the first-order model").
// Private to src/.
#include <array>
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/model/instant.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex::detail {

/// The 5-stage Gauss-Legendre method (order 10, A-stable): nodes c, weights b and the
/// collocation matrix a (a_ij = ∫_0^{c_i} l_j, b_j = ∫_0^1 l_j with l_j the Lagrange
/// polynomials on c), to 21 digits from a 50-digit evaluation (mpmath).
struct GaussTableau {
  static constexpr int s = 5;
  static constexpr std::array<double, 5> c{0.0469100770306680036012, 0.230765344947158454482, 0.5,
                                           0.769234655052841545518, 0.953089922969331996399};
  static constexpr std::array<double, 5> b{0.118463442528094543757, 0.239314335249683234021,
                                           0.284444444444444444444, 0.239314335249683234021,
                                           0.118463442528094543757};
  static constexpr std::array<std::array<double, 5>, 5> a{{
      {0.0592317212640472718786, -0.0195703643590760374926, 0.0112544008186429555527, -0.00559379366081218487682,
       0.00158811296786599853937},
      {0.128151005670045283496, 0.11965716762484161701, -0.0245921146196422003893, 0.010318280670683357409,
       -0.00276899439876960304428},
      {0.113776288004224602529, 0.260004651680641518592, 0.142222222222222222222, -0.0206903164309582845718,
       0.00468715452386994122839},
      {0.121232436926864146801, 0.228996054578999876612, 0.309036559064086644834, 0.11965716762484161701,
       -0.00968756314195073973903},
      {0.116875329560228545218, 0.244908128910495418897, 0.273190043625801488892, 0.258884699608759271513,
       0.0592317212640472718786},
  }};
};

/// x' = M(t, p) x + f(t, p), linear in x for each saturation pattern p (one entry per
/// input: 0 free, +1 / −1 held at its upper / lower limit).
struct SaturatedLinearSystem {
  int dim = 0;
  int inputs = 0;
  /// M and f at `at` under pattern p; false when they are not finite.
  std::function<bool(const Instant& at, const Eigen::VectorXi& p, Eigen::MatrixXd& M, Eigen::VectorXd& f)> matrices;
  /// The pattern the law gives at (at, x).
  std::function<void(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::VectorXi& p)> pattern;
};

struct GaussOptions {
  int steps = 8;               ///< per interval between consecutive edges, >= 1
  long max_total_steps = 0;    ///< Gauss steps (halvings included); 0: no limit
  /// Optional: the study's work budget, charged 40 n³ units a step (a dense LU of the
  /// 5-stage system, 5n unknowns: ~42 n³ flops, against n³ for a Riccati step).
  std::shared_ptr<WorkBudget> budget;
  std::function<void(double t)> progress;  ///< at each output time recorded
};

/// Integrates from x0 at output_times.front() to output_times.back() and records x at
/// each output time. The span is cut into pieces at `breakpoints` (evaluated at
/// Instant{t, piece midpoint}, as integrate() does) and each piece into intervals at the
/// output times and the `grid` times inside it; each interval takes `steps` equal
/// steps. Intervals within round-off of their ends (roundoff_span) are not stepped.
IntegrationResult integrate_gauss(const SaturatedLinearSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x0,
                                  const std::vector<double>& output_times, const std::vector<double>& breakpoints,
                                  const std::vector<double>& grid, const GaussOptions& options);

}  // namespace freeflex::detail
