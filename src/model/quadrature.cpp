// Gauss-Legendre quadrature: nodes and weights, and composite rules on panels.
#include "freeflex/model/quadrature.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace freeflex {

namespace {
/// P_n(x) and P_n'(x) by the three-term recurrence.
std::pair<double, double> legendre(int n, double x) {
  double p0 = 1.0, p1 = x;
  for (int k = 2; k <= n; ++k) {
    const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
    p0 = p1;
    p1 = p2;
  }
  return {p1, n * (x * p1 - p0) / (x * x - 1.0)};
}
}  // namespace

GaussRule gauss_legendre(int n) {
  if (n < 1) throw std::invalid_argument("gauss_legendre: n must be >= 1, got " + std::to_string(n));
  GaussRule r{Eigen::VectorXd(n), Eigen::VectorXd(n)};
  // Newton on P_n from Tricomi's initial guess; converges in a few steps to round-off.
  for (int i = 0; i < (n + 1) / 2; ++i) {
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5));
    for (int it = 0; it < 100; ++it) {
      const auto [p, dp] = legendre(n, x);
      const double dx = p / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    const double dp = legendre(n, x).second;
    const double w = 2.0 / ((1.0 - x * x) * dp * dp);
    r.nodes(i) = -x;
    r.nodes(n - 1 - i) = x;
    r.weights(i) = w;
    r.weights(n - 1 - i) = w;
  }
  if (n % 2 == 1) r.nodes(n / 2) = 0.0;
  return r;
}

GaussRule composite_gauss(double a, double b, int panels, int n) {
  if (!(b > a)) throw std::invalid_argument("composite_gauss: expected b > a");
  if (panels < 1) throw std::invalid_argument("composite_gauss: panels must be >= 1");
  const GaussRule base = gauss_legendre(n);
  GaussRule r{Eigen::VectorXd(panels * n), Eigen::VectorXd(panels * n)};
  const double h = (b - a) / panels;
  for (int p = 0; p < panels; ++p) {
    const double mid = a + (p + 0.5) * h;
    for (int i = 0; i < n; ++i) {
      r.nodes(p * n + i) = mid + 0.5 * h * base.nodes(i);
      r.weights(p * n + i) = 0.5 * h * base.weights(i);
    }
  }
  return r;
}

}  // namespace freeflex
