#pragma once
// Butcher tables of the explicit embedded Runge-Kutta pairs freeflex integrates with
// (sim/runge_kutta.cpp): coefficients typed from the published tables, checked against
// the order conditions in tests/sim/test_runge_kutta.cpp. Private to src/.
#include <vector>

#include <Eigen/Dense>

namespace freeflex::detail {

struct ButcherPair {
  const char* name = "";
  int order = 0;        ///< of the solution kept (local extrapolation)
  int error_order = 0;  ///< of the embedded solution: the step-size exponent is 1/(error_order + 1)
  /// Stages of one step, k_0 = f(t_n, y_n) included; with `fsal` the last of them is
  /// f(t_n + h, y_n+1), which is the next step's k_0 (s - 1 evaluations a step).
  int stages = 0;
  bool fsal = false;
  /// Stages with those only the dense output needs (>= stages).
  int dense_stages = 0;
  std::vector<double> c;               ///< dense_stages nodes
  std::vector<std::vector<double>> a;  ///< row i: a(i, 0..i-1), dense_stages rows
  std::vector<double> b;               ///< stages weights of the solution kept
  std::vector<double> e;               ///< b - b̂: h Σ e_i k_i estimates the local error
  /// DOP853 only (else empty): b - b̂3 of its third-order solution, which its error norm
  /// combines with `e` (Hairer, Nørsett, Wanner, Solving ODE I, II.10).
  std::vector<double> e3;
  /// y(t_n + θh) = y_n + h Σ_i k_i Σ_j dense(i, j) θ^(j+1), i < dense_stages.
  Eigen::MatrixXd dense;
};

/// Dormand and Prince's 8(5,3) pair (Hairer's DOP853): 12 evaluations a step, dense
/// output of order 7 with 3 more.
const ButcherPair& dop853();
/// Verner's 9(8) pair: 16 evaluations a step, dense output of order 9 with 10 more.
const ButcherPair& verner98();

}  // namespace freeflex::detail
