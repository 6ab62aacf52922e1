// detail::small_gemm: n x n products for the Newton solves and the Riccati right-hand
// side of the TV-LQR, register-blocked with AVX2/FMA where the CPU has them.
#include "control/lyapunov_solvers.hpp"

#include <algorithm>
#include <cstddef>

namespace freeflex {

namespace detail {
namespace {

/// The body of small_gemm with W-wide vectors (GCC vector extensions): 2W x 4 blocks of C
/// held in 8 registers over the whole k loop, then W x 4 and 1 x 4 edge blocks.
template <int W>
__attribute__((always_inline)) inline void gemm_body(int n, const double* __restrict A, const double* __restrict B,
                                                     double* __restrict C, bool upper) {
  typedef double V __attribute__((vector_size(W * sizeof(double))));
  const std::ptrdiff_t ld = n;
  for (int j0 = 0; j0 < n; j0 += 4) {
    const int nj = std::min(4, n - j0);
    const int rows = upper ? j0 + nj : n;
    const double* b[4];
    for (int jj = 0; jj < 4; ++jj) b[jj] = B + (j0 + std::min(jj, nj - 1)) * ld;  // narrow block: repeat
    int i0 = 0;
    for (; i0 + 2 * W <= rows; i0 += 2 * W) {
      V c00 = {}, c01 = {}, c10 = {}, c11 = {}, c20 = {}, c21 = {}, c30 = {}, c31 = {};
      const double* a = A + i0;
      for (int k = 0; k < n; ++k, a += ld) {
        V a0, a1;
        __builtin_memcpy(&a0, a, sizeof a0);
        __builtin_memcpy(&a1, a + W, sizeof a1);
        const V b0 = a0 * 0 + b[0][k], b1 = a0 * 0 + b[1][k], b2 = a0 * 0 + b[2][k], b3 = a0 * 0 + b[3][k];
        c00 += a0 * b0;
        c01 += a1 * b0;
        c10 += a0 * b1;
        c11 += a1 * b1;
        c20 += a0 * b2;
        c21 += a1 * b2;
        c30 += a0 * b3;
        c31 += a1 * b3;
      }
      double* c = C + i0 + j0 * ld;
      const V cs[4][2] = {{c00, c01}, {c10, c11}, {c20, c21}, {c30, c31}};
      for (int jj = 0; jj < nj; ++jj) __builtin_memcpy(c + jj * ld, cs[jj], 2 * sizeof(V));
    }
    for (; i0 + W <= rows; i0 += W) {
      V c0 = {}, c1 = {}, c2 = {}, c3 = {};
      const double* a = A + i0;
      for (int k = 0; k < n; ++k, a += ld) {
        V a0;
        __builtin_memcpy(&a0, a, sizeof a0);
        c0 += a0 * b[0][k];
        c1 += a0 * b[1][k];
        c2 += a0 * b[2][k];
        c3 += a0 * b[3][k];
      }
      double* c = C + i0 + j0 * ld;
      const V cs[4] = {c0, c1, c2, c3};
      for (int jj = 0; jj < nj; ++jj) __builtin_memcpy(c + jj * ld, &cs[jj], sizeof(V));
    }
    for (; i0 < rows; ++i0) {
      double sum[4] = {0.0, 0.0, 0.0, 0.0};
      for (int k = 0; k < n; ++k) {
        const double a = A[i0 + k * ld];
        for (int jj = 0; jj < 4; ++jj) sum[jj] += a * b[jj][k];
      }
      for (int jj = 0; jj < nj; ++jj) C[i0 + (j0 + jj) * ld] = sum[jj];
    }
  }
}

__attribute__((target("avx2,fma"))) void gemm_avx2(int n, const double* A, const double* B, double* C, bool upper) {
  gemm_body<4>(n, A, B, C, upper);
}

}  // namespace

void small_gemm(int n, const double* A, const double* B, double* C, bool upper) {
  static const bool avx2 = [] {
    __builtin_cpu_init();  // in case this runs before main (a static initializer)
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  if (avx2) {
    gemm_avx2(n, A, B, C, upper);
    return;
  }
  using Map = Eigen::Map<Eigen::MatrixXd>;
  using CMap = Eigen::Map<const Eigen::MatrixXd>;
  Map Cm(C, n, n);
  if (upper)
    Cm.triangularView<Eigen::Upper>() = CMap(A, n, n) * CMap(B, n, n);
  else
    Cm.noalias() = CMap(A, n, n) * CMap(B, n, n);
}

}  // namespace detail

}  // namespace freeflex
