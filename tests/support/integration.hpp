#pragma once
// Small helpers of the integrator tests: π and evenly spaced output times.
#include <cmath>
#include <vector>

namespace freeflex_test {

inline const double kPi = std::acos(-1.0);

/// n times from a to b, the last exactly b.
inline std::vector<double> linspace(double a, double b, int n) {
  std::vector<double> t(n);
  for (int i = 0; i < n; ++i) t[i] = a + (b - a) * i / (n - 1);
  t.back() = b;
  return t;
}

}  // namespace freeflex_test
