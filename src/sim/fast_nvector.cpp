// Serial N_Vector kernels compiled with the project's flags (see fast_nvector.hpp).
#include "sim/fast_nvector.hpp"

#include <nvector/nvector_serial.h>

#include <cmath>

#include "util/avx2_clones.hpp"

namespace freeflex {
namespace {

inline double* data(N_Vector v) { return NV_DATA_S(v); }
inline sunindextype len(N_Vector v) { return NV_LENGTH_S(v); }

// Each kernel is compiled twice, for AVX2 and for the baseline, and picked at load time
// (util/avx2_clones.hpp): four doubles an instruction instead of two, the same bits.
extern "C" FREEFLEX_AVX2_CLONES void ff_linearsum(sunrealtype a, N_Vector x, sunrealtype b, N_Vector y, N_Vector z) {
  const sunindextype N = len(x);
  const double* xd = data(x);  // z may be x or y
  const double* yd = data(y);
  double* zd = data(z);
  // CVODE's Adams predictor is a chain of z = x + y calls, each reading the last one's
  // result: without the multiplications by one the chain is shorter (same bits).
  if (a == 1.0 && b == 1.0) {
    for (sunindextype i = 0; i < N; ++i) zd[i] = xd[i] + yd[i];
    return;
  }
  // N_VLinearSum_Serial's special cases that round differently from a x + b y
  if (!((b == 1.0 && z == y) || (a == 1.0 && z == x))) {
    const bool lin = a == 1.0 || b == 1.0 || a == -1.0 || b == -1.0;
    if (!lin && a == b) {
      for (sunindextype i = 0; i < N; ++i) zd[i] = a * (xd[i] + yd[i]);
      return;
    }
    if (!lin && a == -b) {
      for (sunindextype i = 0; i < N; ++i) zd[i] = a * (xd[i] - yd[i]);
      return;
    }
  }
  for (sunindextype i = 0; i < N; ++i) zd[i] = a * xd[i] + b * yd[i];
}
extern "C" FREEFLEX_AVX2_CLONES void ff_scale(sunrealtype c, N_Vector x, N_Vector z) {
  const double* xd = data(x);
  double* zd = data(z);
  for (sunindextype i = 0, N = len(x); i < N; ++i) zd[i] = c * xd[i];
}
extern "C" FREEFLEX_AVX2_CLONES sunrealtype ff_wsqrsum(N_Vector x, N_Vector w) {
  // four partial sums: the sequential sum is latency-bound (the only change of rounding)
  const double *xd = data(x), *wd = data(w);
  const sunindextype N = len(x);
  double s[4] = {0.0, 0.0, 0.0, 0.0};
  sunindextype i = 0;
  for (; i + 4 <= N; i += 4)
    for (int l = 0; l < 4; ++l) {
      const double p = xd[i + l] * wd[i + l];
      s[l] += p * p;
    }
  for (; i < N; ++i) {
    const double p = xd[i] * wd[i];
    s[0] += p * p;
  }
  return (s[0] + s[1]) + (s[2] + s[3]);
}
extern "C" sunrealtype ff_wrmsnorm(N_Vector x, N_Vector w) {
  return std::sqrt(ff_wsqrsum(x, w) / static_cast<double>(len(x)));
}
/// Z_i = a_i x + Y_i (the fallback N_VLinearSum(a_i, x, 1, Y_i, Z_i) rounds the same way).
extern "C" FREEFLEX_AVX2_CLONES int ff_scaleaddmulti(int nvec, sunrealtype* a, N_Vector x, N_Vector* Y, N_Vector* Z) {
  const sunindextype N = len(x);
  bool alias = false;
  for (int k = 0; k < nvec; ++k) alias = alias || Z[k] == x;
  if (alias) {
    for (int k = 0; k < nvec; ++k) ff_linearsum(a[k], x, 1.0, Y[k], Z[k]);
    return 0;
  }
  const double* xd = data(x);
  for (int k = 0; k < nvec; ++k) {
    const double* yd = data(Y[k]);
    double* zd = data(Z[k]);
    const double ak = a[k];
    for (sunindextype i = 0; i < N; ++i) zd[i] = ak * xd[i] + yd[i];
  }
  return 0;
}

}  // namespace

void use_compiled_vector_kernels(N_Vector v) {
  N_Vector_Ops o = v->ops;
  o->nvlinearsum = ff_linearsum;
  o->nvscale = ff_scale;
  o->nvwrmsnorm = ff_wrmsnorm;
  o->nvwsqrsumlocal = ff_wsqrsum;
  o->nvscaleaddmulti = ff_scaleaddmulti;
}

}  // namespace freeflex
