#pragma once
// Quintic Hermite interpolation on one interval: the weights that combine value, first
// and second derivative at both ends (scaled by the interval length h, h²) into the
// interpolant and its first two derivatives. Private to src/.

namespace freeflex::detail {

/// Weights at s in [0, 1] of (v0, h r0, h² a0, v1, h r1, h² a1): H gives the value,
/// D1 its derivative in s, D2 its second derivative in s (divide by h and h²).
struct QuinticHermite {
  double H[6], D1[6], D2[6];
  explicit QuinticHermite(double s) {
    const double s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
    const double h[6] = {1 - 10 * s3 + 15 * s4 - 6 * s5, s - 6 * s3 + 8 * s4 - 3 * s5,
                         0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5, 10 * s3 - 15 * s4 + 6 * s5,
                         -4 * s3 + 7 * s4 - 3 * s5, 0.5 * s3 - s4 + 0.5 * s5};
    const double d1[6] = {-30 * s2 + 60 * s3 - 30 * s4, 1 - 18 * s2 + 32 * s3 - 15 * s4,
                          s - 4.5 * s2 + 6 * s3 - 2.5 * s4, 30 * s2 - 60 * s3 + 30 * s4,
                          -12 * s2 + 28 * s3 - 15 * s4, 1.5 * s2 - 4 * s3 + 2.5 * s4};
    const double d2[6] = {-60 * s + 180 * s2 - 120 * s3, -36 * s + 96 * s2 - 60 * s3,
                          1 - 9 * s + 18 * s2 - 10 * s3, 60 * s - 180 * s2 + 120 * s3,
                          -24 * s + 84 * s2 - 60 * s3, 3 * s - 12 * s2 + 10 * s3};
    for (int i = 0; i < 6; ++i) {
      H[i] = h[i];
      D1[i] = d1[i];
      D2[i] = d2[i];
    }
  }
};

}  // namespace freeflex::detail
