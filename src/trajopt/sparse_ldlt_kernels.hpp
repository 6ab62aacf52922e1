#pragma once
// Dense kernel of the sparse LDLᵀ's fronts (sparse_ldlt_kernels.cpp).

namespace freeflex::detail {

/// C(i, j) -= Σ_{c < p} L(i, c) W(j, c) for 0 <= j < cols and j <= i < rows; all three
/// column major with leading dimensions ldl, ldw, ldc. Entries just above the diagonal
/// (within 4-column blocks) may be written too: callers keep only the lower triangle.
void trapezoid_update(int rows, int cols, int p, const double* L, int ldl, const double* W, int ldw, double* C, int ldc);

/// y -= A x (A rows x p, column major with leading dimension lda), returning
/// max_{1 <= i < rows} |y_i| (0 when rows < 2).
double column_update_max(int rows, int p, const double* A, int lda, const double* x, double* y);

/// y -= Aᵀ x: y_c -= Σ_i A(i, c) x_i for c < p, A rows x p as above.
void transposed_update(int rows, int p, const double* A, int lda, const double* x, double* y);

/// Tests only (not thread-safe): the SSE2 kernels everywhere (true), or the CPU's best
/// again (false); returns whether the CPU's own (AVX2) kernels are now in use.
bool use_portable_ldlt_kernels(bool portable);

/// max_i |x_i| over n entries (0 when n <= 0).
double max_abs(const double* x, int n);

}  // namespace freeflex::detail
