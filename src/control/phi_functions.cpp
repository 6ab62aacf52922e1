// φ-functions at complex arguments and on the block operators of a real block-diagonal
// form (control/phi_functions.hpp).
#include "control/phi_functions.hpp"

#include <cmath>

namespace freeflex::detail {

namespace {

using cd = std::complex<double>;

// Below |z| = 1 the series (under 20 terms) is exact to round-off and the upward recurrence
// would cancel; above it the recurrence loses at most a factor (k + 1)/|z| per level
// (~100 ε for φ_4 at |z| = 1).
constexpr double kSeriesRadius = 1.0;
// A block with |t α| below this is treated by Taylor terms in α (truncation (tα)⁴ ~ 1e-12);
// above it the divided differences lose at most ε/|tα| ~ 1e-13.
constexpr double kTaylorRadius = 1e-3;

double factorial(int k) {
  double f = 1.0;
  for (int i = 2; i <= k; ++i) f *= i;
  return f;
}
const double kInverseFactorial[kMaxPhi + 1] = {1.0, 1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0};

/// Σ_j (j+m)!/j! z^j/(j+m+k)!, the m-th derivative of φ_k, to round-off for |z| < 1
/// (at most ~20 terms; the test compares squared magnitudes: no hypot in this loop).
cd phi_series(cd z, int k, int m) {
  cd sum = 0.0, term = factorial(m) / factorial(m + k);  // j = 0
  for (int j = 0; j < 60; ++j) {
    sum += term;
    if (std::norm(term) < 1e-36 * std::norm(sum)) break;
    term *= z * (double(j + m + 1) / (double(j + 1) * double(j + m + k + 1)));
  }
  return sum;
}

using Derivs = std::array<std::array<cd, kMaxPhiDerivative + 1>, kMaxPhi + 1>;

}  // namespace

void phi_values(cd z, int kmax, cd* out) {
  const double zr = z.real(), zi = z.imag(), r2 = zr * zr + zi * zi;
  if (r2 < kSeriesRadius * kSeriesRadius) {
    out[kmax] = phi_series(z, kmax, 0);
    for (int k = kmax - 1; k >= 0; --k) out[k] = kInverseFactorial[k] + z * out[k + 1];  // stable downwards
    return;
  }
  // e^z and the upward recurrence, with 1/z formed once (complex division is slow)
  const double e = std::exp(zr);
  out[0] = cd(e * std::cos(zi), e * std::sin(zi));
  const cd inv(zr / r2, -zi / r2);
  for (int k = 0; k < kmax; ++k) out[k + 1] = (out[k] - kInverseFactorial[k]) * inv;
}

void phi_derivatives(cd z, int kmax, int mmax, Derivs& out) {
  if (std::norm(z) < kSeriesRadius * kSeriesRadius) {
    // the series for k = kmax, then φ_k = 1/k! + z φ_{k+1} differentiated m times,
    // φ_k^(m) = z φ_{k+1}^(m) + m φ_{k+1}^(m−1), downwards (stable for |z| < 1)
    for (int m = 0; m <= mmax; ++m) out[kmax][m] = phi_series(z, kmax, m);
    for (int k = kmax - 1; k >= 0; --k) {
      out[k][0] = kInverseFactorial[k] + z * out[k + 1][0];
      for (int m = 1; m <= mmax; ++m) out[k][m] = z * out[k + 1][m] + double(m) * out[k + 1][m - 1];
    }
    return;
  }
  cd v[kMaxPhi + 1];
  phi_values(z, kmax, v);
  for (int k = 0; k <= kmax; ++k) out[k][0] = v[k];
  for (int m = 1; m <= mmax; ++m) {
    out[0][m] = v[0];
    // z φ_k' = φ_{k−1} − k φ_k, differentiated m − 1 times
    for (int k = 1; k <= kmax; ++k) out[k][m] = (out[k - 1][m - 1] - double(k + m - 1) * out[k][m - 1]) / z;
  }
}

void pair_phi(double t, double c, double det_i, int size_i, double det_j, int size_j, int kmax, PairCoefficients& out) {
  const double a2 = size_i == 2 ? -det_i : 0.0, b2 = size_j == 2 ? -det_j : 0.0;  // α², β²
  const bool small_i = size_i == 1 || t * std::sqrt(std::abs(a2)) < kTaylorRadius;
  const bool small_j = size_j == 1 || t * std::sqrt(std::abs(b2)) < kTaylorRadius;
  for (int k = 0; k <= kmax; ++k) out.a[k] = {0.0, 0.0, 0.0, 0.0};
  if (size_i == 1 && size_j == 1) {  // scalar: the common case of real eigenvalues
    cd v[kMaxPhi + 1];
    phi_values(t * c, kmax, v);
    for (int k = 0; k <= kmax; ++k) out.a[k][0] = v[k].real();
    return;
  }
  if (small_i && small_j) {  // Taylor in both (terms up to fourth order)
    Derivs d;
    phi_derivatives(t * c, kmax, 4, d);
    const double t2 = t * t, t3 = t2 * t, t4 = t2 * t2;
    for (int k = 0; k <= kmax; ++k) {
      const double d0 = d[k][0].real(), d1 = t * d[k][1].real(), d2 = t2 * d[k][2].real(), d3 = t3 * d[k][3].real(),
                   d4 = t4 * d[k][4].real();
      out.a[k][0] = d0 + d2 * (a2 + b2) / 2.0 + d4 * (a2 * a2 + 6.0 * a2 * b2 + b2 * b2) / 24.0;
      out.a[k][1] = d1 + d3 * (a2 / 6.0 + b2 / 2.0);
      out.a[k][2] = d1 + d3 * (b2 / 6.0 + a2 / 2.0);
      out.a[k][3] = d2 + d4 * (a2 + b2) / 6.0;
    }
    return;
  }
  if (small_i != small_j) {  // Taylor in the small one, exact at ±(the other)
    const double s2 = small_i ? a2 : b2;               // the small side's square
    const double x2 = small_i ? b2 : a2;               // the exact side's
    const cd x = std::sqrt(cd(x2, 0.0));
    const cd ix = x2 < 0.0 ? cd(0.0, -1.0 / x.imag()) : cd(1.0 / x.real(), 0.0);
    const bool need_derivs = small_i ? size_i == 2 : size_j == 2;
    if (!need_derivs) {  // a 1x1 block beside a 2x2 one: f at t(c ± x), conjugates if x is imaginary
      cd gp[kMaxPhi + 1], gm[kMaxPhi + 1];
      phi_values(t * (c + x), kmax, gp);
      if (x2 < 0.0) {
        for (int k = 0; k <= kmax; ++k) gm[k] = std::conj(gp[k]);
      } else {
        phi_values(t * (c - x), kmax, gm);
      }
      for (int k = 0; k <= kmax; ++k) {
        out.a[k][0] = 0.5 * (gp[k] + gm[k]).real();
        out.a[k][small_i ? 2 : 1] = (0.5 * (gp[k] - gm[k]) * ix).real();
      }
      return;
    }
    Derivs dp, dm;
    phi_derivatives(t * (c + x), kmax, 3, dp);
    phi_derivatives(t * (c - x), kmax, 3, dm);
    for (int k = 0; k <= kmax; ++k) {
      // e_m(±x) = t^m φ_k^(m)(t(c ± x)); the small side's even and odd parts
      const cd ev_p = dp[k][0] + t * t * dp[k][2] * s2 / 2.0, ev_m = dm[k][0] + t * t * dm[k][2] * s2 / 2.0;
      const cd od_p = t * dp[k][1] + t * t * t * dp[k][3] * s2 / 6.0, od_m = t * dm[k][1] + t * t * t * dm[k][3] * s2 / 6.0;
      out.a[k][0] = (0.5 * (ev_p + ev_m)).real();
      out.a[k][small_i ? 1 : 2] = (0.5 * (od_p + od_m)).real();
      out.a[k][small_i ? 2 : 1] = (0.5 * (ev_p - ev_m) * ix).real();
      out.a[k][3] = (0.5 * (od_p - od_m) * ix).real();
    }
    return;
  }
  // both exact: f at t(c ± α ± β). α and β are real or imaginary, so the four points are
  // two conjugate pairs (f is real on the real axis): two evaluations do.
  const cd al = std::sqrt(cd(a2, 0.0)), be = std::sqrt(cd(b2, 0.0));
  cd g[4][kMaxPhi + 1];  // (+,+), (+,−), (−,+), (−,−)
  const cd zpp = t * (c + al + be), zpm = t * (c + al - be), zmp = t * (c - al + be), zmm = t * (c - al - be);
  phi_values(zpp, kmax, g[0]);
  if (zmm == std::conj(zpp)) {  // α, β both imaginary
    phi_values(zpm, kmax, g[1]);
    for (int k = 0; k <= kmax; ++k) {
      g[3][k] = std::conj(g[0][k]);
      g[2][k] = std::conj(g[1][k]);
    }
  } else if (zpm == std::conj(zpp)) {  // α real, β imaginary
    phi_values(zmp, kmax, g[2]);
    for (int k = 0; k <= kmax; ++k) {
      g[1][k] = std::conj(g[0][k]);
      g[3][k] = std::conj(g[2][k]);
    }
  } else if (zmp == std::conj(zpp)) {  // α imaginary, β real
    phi_values(zpm, kmax, g[1]);
    for (int k = 0; k <= kmax; ++k) {
      g[2][k] = std::conj(g[0][k]);
      g[3][k] = std::conj(g[1][k]);
    }
  } else {
    phi_values(zpm, kmax, g[1]);
    phi_values(zmp, kmax, g[2]);
    phi_values(zmm, kmax, g[3]);
  }
  // α, β are real or imaginary: their inverses without complex division
  const cd ia = a2 < 0.0 ? cd(0.0, -1.0 / al.imag()) : cd(1.0 / al.real(), 0.0);
  const cd ib = b2 < 0.0 ? cd(0.0, -1.0 / be.imag()) : cd(1.0 / be.real(), 0.0);
  const cd iab = ia * ib;
  for (int k = 0; k <= kmax; ++k) {
    out.a[k][0] = 0.25 * (g[0][k] + g[1][k] + g[2][k] + g[3][k]).real();
    out.a[k][1] = (0.25 * (g[0][k] + g[1][k] - g[2][k] - g[3][k]) * ia).real();
    out.a[k][2] = (0.25 * (g[0][k] - g[1][k] + g[2][k] - g[3][k]) * ib).real();
    out.a[k][3] = (0.25 * (g[0][k] - g[1][k] - g[2][k] + g[3][k]) * iab).real();
  }
}

void block_phi(double t, double m, double det, int size, int kmax, BlockCoefficients& out) {
  const double a2 = size == 2 ? -det : 0.0;
  for (int k = 0; k <= kmax; ++k) out.a[k] = {0.0, 0.0};
  if (size == 1) {
    cd v[kMaxPhi + 1];
    phi_values(t * m, kmax, v);
    for (int k = 0; k <= kmax; ++k) out.a[k][0] = v[k].real();
    return;
  }
  if (t * std::sqrt(std::abs(a2)) < kTaylorRadius) {
    Derivs d;
    phi_derivatives(t * m, kmax, 4, d);
    const double t2 = t * t;
    for (int k = 0; k <= kmax; ++k) {
      out.a[k][0] = (d[k][0] + t2 * d[k][2] * a2 / 2.0 + t2 * t2 * d[k][4] * a2 * a2 / 24.0).real();
      out.a[k][1] = (t * d[k][1] + t * t2 * d[k][3] * a2 / 6.0).real();
    }
    return;
  }
  const cd al = std::sqrt(cd(a2, 0.0));
  const cd ia = a2 < 0.0 ? cd(0.0, -1.0 / al.imag()) : cd(1.0 / al.real(), 0.0);
  cd gp[kMaxPhi + 1], gm[kMaxPhi + 1];
  phi_values(t * (m + al), kmax, gp);
  if (a2 < 0.0) {  // a complex pair: the second point is the conjugate
    for (int k = 0; k <= kmax; ++k) gm[k] = std::conj(gp[k]);
  } else {
    phi_values(t * (m - al), kmax, gm);
  }
  for (int k = 0; k <= kmax; ++k) {
    out.a[k][0] = (0.5 * (gp[k] + gm[k])).real();
    out.a[k][1] = (0.5 * (gp[k] - gm[k]) * ia).real();
  }
}

}  // namespace freeflex::detail
