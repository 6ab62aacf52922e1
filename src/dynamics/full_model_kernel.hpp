#pragma once
// The full model's right-hand side at run-time size (private to src/): what the kernels
// FullModel::rhs compiles for common sizes must equal, to the bit in a default build.
#include <Eigen/Dense>

#include "freeflex/dynamics/full_model.hpp"

namespace freeflex::detail {

/// With geometric stiffening the kinetic energy is kept to second order in q: once
/// det 𝕄_b(q) / det 𝕄_b(0) falls to this ratio the dropped higher-order terms are of the
/// size of what is left, and the state is out of the model's range (FullModel::rhs).
constexpr double kMinMassDeterminantRatio = 1e-3;

/// The end of the stiffened model's right-hand side (eq. 14.5-14.6), in any elastic
/// coordinates: 𝕄_b(q) = 𝕄_b(0) + U S Uᵀ with U = [e_x, e_y, e_θ, v], v = [0; 0; 0; H̄q],
/// S(x,θ) = −Φ̄q, S(y,θ) = −½ qᵀH̄q, S(θ,θ) = qᵀ(M − G_c)q, S(x,v) = −1. On entry the
/// last 3+n entries of x_dot hold y = 𝕄_b(0)⁻¹ g, WU the columns 𝕄_b(0)⁻¹ [e_x, e_y, e_θ, v]
/// (Wv the last of them); on return they hold z'' with R'' in inertial axes (c, s: cos θ,
/// sin θ), by w = y − W U S (I + Uᵀ W U S)⁻¹ Uᵀ y. False when 𝕄_b(q) has lost all but
/// kMinMassDeterminantRatio of its determinant at rest.
bool stiffened_correction(Eigen::VectorXd& x_dot, const Eigen::Matrix<double, Eigen::Dynamic, 4>& WU,
                          const Eigen::VectorXd& Wv, const Eigen::VectorXd& Hq, double Pq, double qHq, double qMq,
                          double c, double s);

/// FullModel::rhs (without geometric stiffening) through the kernel whose number of
/// elastic coordinates is a run-time value, whatever the body's size, summing in the order
/// FullModel::rhs takes for that size.
bool full_rhs_runtime_size(const FullModel& model, FullModel::Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                           const Eigen::Ref<const Eigen::VectorXd>& commands);

/// The run-time-size kernel with every sum in sequential order, as the kernels of NOA 4-10
/// sum (FullModel::rhs takes the split order for the other sizes): a reference for it.
bool full_rhs_sequential(const FullModel& model, FullModel::Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                         const Eigen::Ref<const Eigen::VectorXd>& commands);

/// FullModel::rhs for a size without a kernel of its own (not NOA 4-10), through the
/// variant with 512-bit vectors when `avx512` and the processor has AVX-512, else through
/// the AVX2 or baseline one: all three give the same bits.
bool full_rhs_large(const FullModel& model, FullModel::Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                    const Eigen::Ref<const Eigen::VectorXd>& commands, bool avx512);
/// Whether this build and processor have the AVX-512 variant.
bool full_rhs_avx512_available();

}  // namespace freeflex::detail
