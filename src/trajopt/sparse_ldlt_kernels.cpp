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
          const V b = a0 * 0 + w[jj][cw];
          c0[jj][0] -= a0 * b;
          c0[jj][1] -= a1 * b;
        }
      }
      for (int jj = 0; jj < nj; ++jj) {
        __builtin_memcpy(C + i0 + (j0 + jj) * ldc, &c0[jj][0], sizeof(V));
        __builtin_memcpy(C + i0 + W + (j0 + jj) * ldc, &c0[jj][1], sizeof(V));
      }
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

/// y -= A x, four columns of A at a time.
template <int W>
__attribute__((always_inline)) inline void column_body(int rows, int p, const double* __restrict A, std::ptrdiff_t lda,
                                                       const double* __restrict x, double* __restrict y) {
  int c = 0;
  for (; c + 4 <= p; c += 4) {
    const double* a0 = A + c * lda;
    const double* a1 = a0 + lda;
    const double* a2 = a1 + lda;
    const double* a3 = a2 + lda;
    const double x0 = x[c], x1 = x[c + 1], x2 = x[c + 2], x3 = x[c + 3];
    for (int i = 0; i < rows; ++i) y[i] -= a0[i] * x0 + a1[i] * x1 + a2[i] * x2 + a3[i] * x3;
  }
  for (; c < p; ++c) {
    const double* a = A + c * lda;
    const double xc = x[c];
    for (int i = 0; i < rows; ++i) y[i] -= a[i] * xc;
  }
}

__attribute__((target("avx2,fma"))) void column_avx2(int rows, int p, const double* A, std::ptrdiff_t lda,
                                                     const double* x, double* y) {
  column_body<4>(rows, p, A, lda, x, y);
}
void column_sse2(int rows, int p, const double* A, std::ptrdiff_t lda, const double* x, double* y) {
  column_body<2>(rows, p, A, lda, x, y);
}

/// The kernels of the CPU, chosen once when the program starts.
struct Kernels {
  decltype(&update_sse2) update;
  decltype(&column_sse2) column;
  decltype(&max_abs_sse2) max_abs;
};

Kernels choose() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return {update_avx2, column_avx2, max_abs_avx2};
  return {update_sse2, column_sse2, max_abs_sse2};
}

const Kernels kernels = choose();

}  // namespace

void column_update(int rows, int p, const double* A, int lda, const double* x, double* y) {
  if (rows > 0 && p > 0) kernels.column(rows, p, A, lda, x, y);
}

double max_abs(const double* x, int n) { return kernels.max_abs(x, n); }

void trapezoid_update(int rows, int cols, int p, const double* L, int ldl, const double* Wm, int ldw, double* C,
                      int ldc) {
  if (rows > 0 && cols > 0 && p > 0) kernels.update(rows, cols, p, L, ldl, Wm, ldw, C, ldc);
}

}  // namespace freeflex::detail
