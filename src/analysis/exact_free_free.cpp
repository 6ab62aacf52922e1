// The closed-form free-free uniform beam: its roots and mode shapes.
#include "freeflex/analysis/exact_free_free.hpp"

#include <cmath>
#include <stdexcept>

namespace freeflex {

double free_free_root(int k) {
  if (k < 1) throw std::invalid_argument("free_free_root: k must be >= 1");
  // cos l - 1/cosh l has the same roots and stays O(1); asymptote (2k+1) pi / 2.
  double l = (2.0 * k + 1.0) * M_PI / 2.0;
  for (int it = 0; it < 50; ++it) {
    const double f = std::cos(l) - 1.0 / std::cosh(l);
    const double df = -std::sin(l) + std::tanh(l) / std::cosh(l);
    const double dl = f / df;
    l -= dl;
    if (std::abs(dl) < 1e-15 * l) break;
  }
  return l;
}

double free_free_shape(int k, double xi) {
  const double l = free_free_root(k);
  const double z = l * xi;
  // sigma = (cosh l - cos l)/(sinh l - sin l); scaled by e^-l as in the cantilever basis:
  // 1 - sigma = (cos l - sin l - e^-l)/(sinh l - sin l).
  const double em = std::exp(-l);
  const double D = 0.5 * (1.0 - em * em) - std::sin(l) * em;  // (sinh l - sin l) e^-l
  const double sigma = (0.5 * (1.0 + em * em) - std::cos(l) * em) / D;
  const double growth = (std::cos(l) - std::sin(l) - em) / D;  // (1 - sigma) e^l
  const double ch_sh = 0.5 * (growth * std::exp(z - l) + (1.0 + sigma) * std::exp(-z));
  return ch_sh + std::cos(z) - sigma * std::sin(z);
}

}  // namespace freeflex
