#pragma once
// Four doubles as one value, for kernels that keep four partial sums (lanes) per loop:
// GCC's vector extension (two SSE2 registers in the baseline, one in an AVX2 clone),
// elsewhere a plain struct with the same per-lane arithmetic. Loads and stores go through
// memcpy (no alignment assumed). Values pass only between inlined helpers, so no call's
// ABI depends on the vector width. Private to src/.
#include <cstring>

#include "util/avx2_clones.hpp"

namespace freeflex::util {

#if defined(__GNUC__)
typedef double V4 __attribute__((vector_size(32)));
#else
struct V4 {
  double v[4];
  double& operator[](int i) { return v[i]; }
  double operator[](int i) const { return v[i]; }
  V4& operator+=(const V4& o) {
    for (int i = 0; i < 4; ++i) v[i] += o.v[i];
    return *this;
  }
  friend V4 operator+(V4 a, const V4& b) { return a += b; }
  friend V4 operator-(V4 a, const V4& b) {
    for (int i = 0; i < 4; ++i) a.v[i] -= b.v[i];
    return a;
  }
  friend V4 operator*(V4 a, const V4& b) {
    for (int i = 0; i < 4; ++i) a.v[i] *= b.v[i];
    return a;
  }
};
#endif

FREEFLEX_ALWAYS_INLINE V4 load4(const double* p) {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
FREEFLEX_ALWAYS_INLINE void store4(double* p, V4 v) { std::memcpy(p, &v, sizeof v); }
FREEFLEX_ALWAYS_INLINE V4 splat4(double x) { return V4{x, x, x, x}; }
/// (l0 + l1) + (l2 + l3)
FREEFLEX_ALWAYS_INLINE double lane_sum(V4 v) { return (v[0] + v[1]) + (v[2] + v[3]); }

}  // namespace freeflex::util
