#pragma once
// Taylor-series integration of the first-order (LTV) model (docs/theory.md section 8,
// "Taylor integration of the perturbation solution"). Internal to the simulations.
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/sim/integrator.hpp"

namespace freeflex::detail {

/// The first-order model in body coordinates (R1 and its rate turned by -θ0), with q in
/// the rest modes and their rates divided by ω (y = S⁻¹ x_b), written as
///   y' = Σ_i c_i(t) (A_i y + g_i)
/// with the coefficient functions c = [1, θ0', θ0'², θ0'', a_x, a_y] (a = C(θ0)ᵀ R0'', the
/// nominal acceleration in the body frame) and u_e, u_e cos θ0, u_e sin θ0 for each
/// element's nominal command u_e. Found from the model itself at frozen nominal states,
/// and checked at random ones.
/// A sparse matrix as its entries (row, column, value), by rows: the terms of the form
/// are sparse in y (about 250 entries in all at 20 functions, against 2 116 of a dense
/// matrix). One whose entries fill at least 30% of the box around them is applied as
/// that dense box instead (the centrifugal term: 132 entries in a 22 x 20 box at NOA 20),
/// a vectorized product some three times cheaper than the entries one by one.
struct SparseEntries {
  std::vector<int> row, col;
  std::vector<double> val;
  bool dense = false;
  int r0 = 0, c0 = 0;  ///< the box's corner
  Eigen::MatrixXd box;
  /// Otherwise the entries on the two half-diagonals (column = row ± n/2: a position's
  /// rate, a rate's stiffness; the oscillators of the rest modes) as vectors, and the
  /// rest one by one.
  Eigen::VectorXd upper, lower;
  std::vector<int> rest;  ///< indices into row, col, val
  std::vector<int> rest_row, rest_col;
  std::vector<double> rest_val;
  explicit SparseEntries(const Eigen::MatrixXd& A = Eigen::MatrixXd());
  int size() const { return static_cast<int>(val.size()); }
  /// The box or the half-diagonals and the rest from val (after val changed).
  void refresh();
  /// acc += this x
  void multiply_add(const double* x, double* acc) const {
    if (dense) {
      Eigen::Map<Eigen::VectorXd>(acc + r0, box.rows()).noalias() +=
          box * Eigen::Map<const Eigen::VectorXd>(x + c0, box.cols());
      return;
    }
    const Eigen::Index h = upper.size();
    if (h > 0) {
      Eigen::Map<Eigen::VectorXd>(acc, h).array() += upper.array() * Eigen::Map<const Eigen::ArrayXd>(x + h, h);
      Eigen::Map<Eigen::VectorXd>(acc + h, h).array() += lower.array() * Eigen::Map<const Eigen::ArrayXd>(x, h);
    }
    const int m = static_cast<int>(rest_val.size());
    for (int e = 0; e < m; ++e) acc[rest_row[e]] += rest_val[e] * x[rest_col[e]];
  }
};

struct LtvForm {
  int n = 0;                          ///< 2N
  std::vector<Eigen::MatrixXd> A;     ///< one per coefficient function (empty: zero)
  std::vector<Eigen::VectorXd> g;     ///< one per coefficient function (empty: zero)
  Eigen::MatrixXd S, S_inv;           ///< x_b = S y
  Eigen::VectorXd omega;              ///< the rest modes' ω
  int N = 0;
  /// Largest misfit of the form against the model at random states (ltv_form_misfit).
  double misfit = 0.0;
  std::string unsupported;            ///< why the model is not of this form (empty: it is)
};

/// Largest misfit of a form that is used (ltv_form_misfit): round-off is 2e-12 at NOA 6
/// to 4e-10 at NOA 40; a term the form lacks (a load the functions do not describe) shows
/// as 1e-5 or more.
inline constexpr double kMaxMisfit = 1e-7;

/// Builds the form for `body` (no inputs: u1 = 0). The scales are the typical sizes of
/// θ0', of θ0'' and |R0''|, and of the commands (for the differences and the check; 0: 1).
LtvForm ltv_form(const FlexibleBody& body, double rate_scale, double accel_scale, double command_scale);
/// The form's largest misfit against the model at four random nominal states of those
/// sizes: A against its largest entry, g row by row against the size of the row's terms.
double ltv_form_misfit(const LtvForm& form, const FlexibleBody& body, double rate_scale, double accel_scale,
                       double command_scale);

/// The coefficient functions c(t) and θ0(t) along a nominal motion.
struct LtvCoefficients {
  const RigidTrajectory* nominal = nullptr;
  CommandFunction commands;
  /// The size of each coefficient function over the run (> 0): changes below
  /// 1e-2 rtol of it are taken as none.
  Eigen::VectorXd scale;
  /// c (size 6 + 3m) and θ0 at `at`; `u` is scratch of m entries.
  void at(const Instant& at, Eigen::Ref<Eigen::VectorXd> c, double& theta0, Eigen::VectorXd& u) const;
};

/// Integrates x1' = A(t) x1 + g(t) from x1 = 0 at output_times.front() and records x1
/// (inertial coordinates, as FirstOrderModel) at each output time. Pieces between
/// `breakpoints` on which every coefficient function is constant are advanced by exact
/// matrix exponentials; the others by Taylor series of the order `order`, the step set so
/// that the series' last terms meet rtol and atol. rhs_evaluations counts Taylor terms
/// (each about one product with a matrix of the model's size).
IntegrationResult integrate_ltv_taylor(const LtvForm& form, const LtvCoefficients& coefficients,
                                       const std::vector<double>& output_times, const std::vector<double>& breakpoints,
                                       const IntegratorOptions& options, int order,
                                       const std::function<std::string(const Instant&, const Eigen::Ref<const Eigen::VectorXd>&)>&
                                           range_check);

}  // namespace freeflex::detail
