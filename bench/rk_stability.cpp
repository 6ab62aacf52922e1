// Not a benchmark: where the explicit pairs' stability polynomials leave the unit disc on
// the imaginary axis (issue 19: is a NOA-20 run held by the stability of its highest mode
// or by accuracy?). For y' = λy each stage is Y_i = 1 + z Σ_j a_ij Y_j and the step
// multiplies y by R(z) = 1 + z Σ_i b_i Y_i, z = hλ; an undamped mode of frequency ω has
// λ = iω, so |R(i h ω)| <= 1 bounds h ω. Prints the boundary and |R| at some h ω.
//
//   build/bench/rk_stability
#include <complex>
#include <cstdio>
#include <vector>

#include "sim/rk_tableaus.hpp"

using freeflex::detail::ButcherPair;

namespace {

std::complex<double> amplification(const ButcherPair& t, std::complex<double> z) {
  std::vector<std::complex<double>> Y(static_cast<std::size_t>(t.stages));
  std::complex<double> y = 1.0;
  for (int i = 0; i < t.stages; ++i) {
    std::complex<double> v = 1.0;
    for (int j = 0; j < i; ++j) v += z * t.a[i][j] * Y[j];
    Y[i] = v;
    y += z * t.b[i] * v;
  }
  return y;
}

}  // namespace

int main() {
  // the classical fourth-order method, whose bound 2√2 = 2.828 is known: a check of the above
  ButcherPair rk4;
  rk4.name = "classical RK4 (check: 2.828)";
  rk4.stages = 4;
  rk4.a = {{}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}};
  rk4.b = {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0};
  const ButcherPair* pairs[] = {&rk4, &freeflex::detail::dop853(), &freeflex::detail::verner98()};
  for (const ButcherPair* t : pairs) {
    const int evaluations = t->fsal ? t->stages - 1 : t->stages;
    double boundary = 0.0;
    for (int k = 1; k <= 20000; ++k) {  // steps of 1e-3 up to h ω = 20
      const double y = 1e-3 * k;
      if (std::abs(amplification(*t, {0.0, y})) > 1.0 + 1e-12) break;
      boundary = y;
    }
    std::printf("%s: |R(i y)| <= 1 up to y = %.3f; %d evaluations a step, %.3f per evaluation\n", t->name, boundary,
                evaluations, boundary / evaluations);
    for (double y : {1.0, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0})
      std::printf("  h omega = %.1f: |R| = %.8f\n", y, std::abs(amplification(*t, {0.0, y})));
  }
  return 0;
}
