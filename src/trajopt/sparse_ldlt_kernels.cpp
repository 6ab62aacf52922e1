// The dense kernel of the sparse LDLᵀ's fronts, C -= L Wᵀ on a lower trapezoid, register
// blocked with GCC vector extensions: AVX2/FMA where the CPU has them (chosen once at run
// time), SSE2 otherwise. Eigen is not used here on purpose: its templates compiled for two
// instruction sets in one program would collide at link time.
#include "trajopt/sparse_ldlt_kernels.hpp"

#include <algorithm>
#include <cstddef>

namespace freeflex::detail {
namespace {

/// W doubles in one vector register (a class template: GCC drops vector_size from a
/// typedef that depends on a function template's parameter when it checks the body).
template <int W>
struct Vec {
  typedef double type __attribute__((vector_size(W * sizeof(double))));
};

/// x in every lane: one broadcast instruction. (Written as `v * 0 + x` it costs a
/// multiply-add more, which the compiler must keep for v's infinities and signed zeros.)
/// (An out-parameter: a vector return value from a function without the AVX target
/// would change the ABI.)
template <class V, int W>
__attribute__((always_inline)) inline void splat(V& v, double x) {
  for (int l = 0; l < W; ++l) v[l] = x;
}

/// C(i, j) -= Σ_c L(i, c) W(j, c) for j < cols and j <= i < rows, by blocks of 2W rows x 4
/// columns (a block that straddles the diagonal also updates entries above it).
template <int W>
__attribute__((always_inline)) inline void update_body(int rows, int cols, int p, const double* __restrict L,
                                                       std::ptrdiff_t ldl, const double* __restrict Wm,
                                                       std::ptrdiff_t ldw, double* __restrict C, std::ptrdiff_t ldc) {
  typedef typename Vec<W>::type V;
  for (int j0 = 0; j0 < cols; j0 += 4) {
    const int nj = std::min(4, cols - j0);
    const double* w[4];
    for (int jj = 0; jj < 4; ++jj) w[jj] = Wm + j0 + std::min(jj, nj - 1);  // narrow block: repeat
    int i0 = j0;
    for (; i0 + 2 * W <= rows; i0 += 2 * W) {
      V c0[4][2];
      for (int jj = 0; jj < 4; ++jj) {
        __builtin_memcpy(&c0[jj][0], C + i0 + (j0 + std::min(jj, nj - 1)) * ldc, sizeof(V));
        __builtin_memcpy(&c0[jj][1], C + i0 + W + (j0 + std::min(jj, nj - 1)) * ldc, sizeof(V));
      }
      const double* l = L + i0;
      for (int c = 0; c < p; ++c, l += ldl) {
        V a0, a1;
        __builtin_memcpy(&a0, l, sizeof a0);
        __builtin_memcpy(&a1, l + W, sizeof a1);
        const std::ptrdiff_t cw = c * ldw;
        for (int jj = 0; jj < 4; ++jj) {
          V b;
          splat<V, W>(b, w[jj][cw]);
          c0[jj][0] -= a0 * b;
          c0[jj][1] -= a1 * b;
        }
      }
      for (int jj = 0; jj < nj; ++jj) {
        __builtin_memcpy(C + i0 + (j0 + jj) * ldc, &c0[jj][0], sizeof(V));
        __builtin_memcpy(C + i0 + W + (j0 + jj) * ldc, &c0[jj][1], sizeof(V));
      }
    }
    if (i0 + W <= rows) {  // one block of W rows
      V c0[4];
      for (int jj = 0; jj < 4; ++jj)
        __builtin_memcpy(&c0[jj], C + i0 + (j0 + std::min(jj, nj - 1)) * ldc, sizeof(V));
      const double* l = L + i0;
      for (int c = 0; c < p; ++c, l += ldl) {
        V a0;
        __builtin_memcpy(&a0, l, sizeof a0);
        const std::ptrdiff_t cw = c * ldw;
        for (int jj = 0; jj < 4; ++jj) {
          V b;
          splat<V, W>(b, w[jj][cw]);
          c0[jj] -= a0 * b;
        }
      }
      for (int jj = 0; jj < nj; ++jj) __builtin_memcpy(C + i0 + (j0 + jj) * ldc, &c0[jj], sizeof(V));
      i0 += W;
    }
    for (; i0 < rows; ++i0) {
      double s[4] = {0.0, 0.0, 0.0, 0.0};
      const double* l = L + i0;
      for (int c = 0; c < p; ++c, l += ldl)
        for (int jj = 0; jj < 4; ++jj) s[jj] += *l * w[jj][c * ldw];
      for (int jj = 0; jj < nj; ++jj) C[i0 + (j0 + jj) * ldc] -= s[jj];
    }
  }
}

__attribute__((target("avx2,fma"))) void update_avx2(int rows, int cols, int p, const double* L, std::ptrdiff_t ldl,
                                                     const double* Wm, std::ptrdiff_t ldw, double* C, std::ptrdiff_t ldc) {
  update_body<4>(rows, cols, p, L, ldl, Wm, ldw, C, ldc);
}

void update_sse2(int rows, int cols, int p, const double* L, std::ptrdiff_t ldl, const double* Wm, std::ptrdiff_t ldw,
                 double* C, std::ptrdiff_t ldc) {
  update_body<2>(rows, cols, p, L, ldl, Wm, ldw, C, ldc);
}

template <int W>
__attribute__((always_inline)) inline double max_abs_body(const double* x, int n) {
  typedef typename Vec<W>::type V;
  V m = {};
  int i = 0;
  for (; i + W <= n; i += W) {
    V v;
    __builtin_memcpy(&v, x + i, sizeof v);
    v = v < 0 ? -v : v;
    m = v > m ? v : m;
  }
  double g = 0.0;
  for (int l = 0; l < W; ++l) g = m[l] > g ? m[l] : g;
  for (; i < n; ++i) g = std::max(g, x[i] < 0 ? -x[i] : x[i]);
  return g;
}

__attribute__((target("avx2,fma"))) double max_abs_avx2(const double* x, int n) { return max_abs_body<4>(x, n); }
double max_abs_sse2(const double* x, int n) { return max_abs_body<2>(x, n); }

/// y -= A x (A rows x p), then max_{i >= 1} |y_i|: by blocks of 2W rows held in
/// registers while the p columns go by, so the column is read and written once.
template <int W>
__attribute__((always_inline)) inline double column_max_body(int rows, int p, const double* __restrict A,
                                                             std::ptrdiff_t lda, const double* __restrict x,
                                                             double* __restrict y) {
  typedef typename Vec<W>::type V;
  {
    double s = y[0];
    for (int c = 0; c < p; ++c) s -= A[c * lda] * x[c];
    y[0] = s;
  }
  V mx = {};
  int i = 1;
  for (; i + 2 * W <= rows; i += 2 * W) {
    V y0, y1;
    __builtin_memcpy(&y0, y + i, sizeof y0);
    __builtin_memcpy(&y1, y + i + W, sizeof y1);
    const double* a = A + i;
    for (int c = 0; c < p; ++c, a += lda) {
      V a0, a1, b;
      __builtin_memcpy(&a0, a, sizeof a0);
      __builtin_memcpy(&a1, a + W, sizeof a1);
      splat<V, W>(b, x[c]);
      y0 -= a0 * b;
      y1 -= a1 * b;
    }
    __builtin_memcpy(y + i, &y0, sizeof y0);
    __builtin_memcpy(y + i + W, &y1, sizeof y1);
    y0 = y0 < 0 ? -y0 : y0;
    y1 = y1 < 0 ? -y1 : y1;
    mx = y0 > mx ? y0 : mx;
    mx = y1 > mx ? y1 : mx;
  }
  double g = 0.0;
  for (int l = 0; l < W; ++l) g = mx[l] > g ? mx[l] : g;
  for (; i < rows; ++i) {
    double s = y[i];
    for (int c = 0; c < p; ++c) s -= A[i + c * lda] * x[c];
    y[i] = s;
    g = std::max(g, s < 0 ? -s : s);
  }
  return g;
}

__attribute__((target("avx2,fma"))) double column_max_avx2(int rows, int p, const double* A, std::ptrdiff_t lda,
                                                           const double* x, double* y) {
  return column_max_body<4>(rows, p, A, lda, x, y);
}
double column_max_sse2(int rows, int p, const double* A, std::ptrdiff_t lda, const double* x, double* y) {
  return column_max_body<2>(rows, p, A, lda, x, y);
}

/// y_c -= Σ_i A(i, c) x_i for c < p (A rows x p): four columns at a time, each with W
/// partial sums.
template <int W>
__attribute__((always_inline)) inline void transposed_body(int rows, int p, const double* __restrict A,
                                                           std::ptrdiff_t lda, const double* __restrict x,
                                                           double* __restrict y) {
  typedef typename Vec<W>::type V;
  int c = 0;
  for (; c + 4 <= p; c += 4) {
    V acc[4] = {};
    int i = 0;
    for (; i + W <= rows; i += W) {
      V xv;
      __builtin_memcpy(&xv, x + i, sizeof xv);
      for (int j = 0; j < 4; ++j) {
        V a;
        __builtin_memcpy(&a, A + i + (c + j) * lda, sizeof a);
        acc[j] += a * xv;
      }
    }
    for (int j = 0; j < 4; ++j) {
      double s = 0.0;
      for (int l = 0; l < W; ++l) s += acc[j][l];
      for (int t = i; t < rows; ++t) s += A[t + (c + j) * lda] * x[t];
      y[c + j] -= s;
    }
  }
  for (; c < p; ++c) {
    V acc = {};
    int i = 0;
    for (; i + W <= rows; i += W) {
      V xv, a;
      __builtin_memcpy(&xv, x + i, sizeof xv);
      __builtin_memcpy(&a, A + i + c * lda, sizeof a);
      acc += a * xv;
    }
    double s = 0.0;
    for (int l = 0; l < W; ++l) s += acc[l];
    for (; i < rows; ++i) s += A[i + c * lda] * x[i];
    y[c] -= s;
  }
}

__attribute__((target("avx2,fma"))) void transposed_avx2(int rows, int p, const double* A, std::ptrdiff_t lda,
                                                         const double* x, double* y) {
  transposed_body<4>(rows, p, A, lda, x, y);
}
void transposed_sse2(int rows, int p, const double* A, std::ptrdiff_t lda, const double* x, double* y) {
  transposed_body<2>(rows, p, A, lda, x, y);
}

/// The kernels of the CPU, chosen once when the program starts.
struct Kernels {
  decltype(&update_sse2) update;
  decltype(&column_max_sse2) column_max;
  decltype(&transposed_sse2) transposed;
  decltype(&max_abs_sse2) max_abs;
};

constexpr Kernels kPortable{update_sse2, column_max_sse2, transposed_sse2, max_abs_sse2};

Kernels choose() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    return {update_avx2, column_max_avx2, transposed_avx2, max_abs_avx2};
  return kPortable;
}

Kernels kernels = choose();

}  // namespace

bool use_portable_ldlt_kernels(bool portable) {
  kernels = portable ? kPortable : choose();
  return kernels.update != kPortable.update;
}

double column_update_max(int rows, int p, const double* A, int lda, const double* x, double* y) {
  return rows > 0 ? kernels.column_max(rows, p, A, lda, x, y) : 0.0;
}

void transposed_update(int rows, int p, const double* A, int lda, const double* x, double* y) {
  if (rows > 0 && p > 0) kernels.transposed(rows, p, A, lda, x, y);
}

double max_abs(const double* x, int n) { return kernels.max_abs(x, n); }

void trapezoid_update(int rows, int cols, int p, const double* L, int ldl, const double* Wm, int ldw, double* C,
                      int ldc) {
  if (rows > 0 && cols > 0 && p > 0) kernels.update(rows, cols, p, L, ldl, Wm, ldw, C, ldc);
}

}  // namespace freeflex::detail
