#pragma once
// The φ-functions of exponential integrators, φ0(z) = e^z, φ_{k+1}(z) = (φ_k(z) − 1/k!)/z,
// evaluated at complex z and applied to the operators of a real block-diagonal form
// (ModalLyapunovSolver): on a 1x1 or 2x2 diagonal block D = m I + N (N trace-free, N² =
// −det N I) and on a pair of blocks, X ↦ D_Iᵀ X + X D_J, whose parts P = N_Iᵀ· and
// Q = ·N_J commute with P² = −det_I, Q² = −det_J. Any f of such an operator is
//   f(t(c + P + Q)) = a0 + a1 P + a2 Q + a3 P Q,
// with a's from f at the four points t(c ± α ± β) (α² = −det_I, β² = −det_J) when the
// blocks' eigenvalues are well apart, and from Taylor terms in α, β (derivatives of f at
// t c) when a block is near defective (|tα| small: divided differences would cancel).
// Private to src/; used by control/riccati_exponential.cpp.
#include <array>
#include <complex>

namespace freeflex::detail {

/// Highest φ index and derivative order the functions below provide.
constexpr int kMaxPhi = 5;
constexpr int kMaxPhiDerivative = 4;

/// φ_0(z) .. φ_kmax(z) into out[0..kmax] (kmax <= kMaxPhi): the Taylor series for |z| < 1,
/// the recurrence from e^z beyond.
void phi_values(std::complex<double> z, int kmax, std::complex<double>* out);

/// d^m/dz^m φ_k(z) into out[k][m], k <= kmax, m <= mmax (<= kMaxPhiDerivative).
void phi_derivatives(std::complex<double> z, int kmax, int mmax,
                     std::array<std::array<std::complex<double>, kMaxPhiDerivative + 1>, kMaxPhi + 1>& out);

/// Coefficients a0..a3 of φ_k(t(c + P + Q)) for k = 0..kmax (see above); a block of size
/// 1 has det = 0 and its coefficients a1 (a2) and a3 are not needed (returned as 0).
/// `det_i`, `det_j`: det N of the two blocks; `size_i`, `size_j`: 1 or 2.
struct PairCoefficients {
  std::array<std::array<double, 4>, kMaxPhi + 1> a;
};
void pair_phi(double t, double c, double det_i, int size_i, double det_j, int size_j, int kmax, PairCoefficients& out);

/// The same for one block, f(t(m + Nᵀ)) = a0 + a1 Nᵀ (vectors transformed by Dᵀ).
struct BlockCoefficients {
  std::array<std::array<double, 2>, kMaxPhi + 1> a;
};
void block_phi(double t, double m, double det, int size, int kmax, BlockCoefficients& out);

}  // namespace freeflex::detail
