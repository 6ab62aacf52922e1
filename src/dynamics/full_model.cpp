// The full nonlinear model (eq. 6.2): residual, right-hand side, invariants.
#include "freeflex/dynamics/full_model.hpp"

#include "dynamics/full_model_kernel.hpp"

#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstring>

#include "dynamics/body_kernels.hpp"
#include "util/avx2_clones.hpp"
#include "util/vec4.hpp"
#include "planar.hpp"

namespace freeflex {
using detail::kMinMassDeterminantRatio;
namespace {
using planar::rot;
const Eigen::Matrix2d& kJ = planar::J();
}  // namespace

FullModel::FullModel(const FlexibleBody& body) : body_(body) {
  const int N = body_.dofs();
  const Eigen::MatrixXd Mb0 = body_.mass_matrix(0.0, Eigen::VectorXd::Zero(body_.n()));
  // 𝕄_b(0) is symmetric positive definite and well conditioned (the basis is orthogonal in
  // M): its inverse, formed once, turns each solve into one matrix-vector product.
  rest_inverse_ = Mb0.llt().solve(Eigen::MatrixXd::Identity(N, N));
  // its columns padded with zeros to a multiple of four rows, for the kernels of fixed size
  rest_inverse_padded_ = Eigen::MatrixXd::Zero((N + 3) / 4 * 4, N);
  rest_inverse_padded_.topRows(N) = rest_inverse_;
  mq_inverse_ = body_.integrals().M.llt().solve(Eigen::MatrixXd::Identity(body_.n(), body_.n()));
}

FullModel::Data FullModel::create_data() const {
  const int N = body_.dofs();
  Data d;
  d.x_dot.resize(2 * N);
  d.G.resize(N);
  d.b.resize(N);
  d.Mq.resize(body_.n());
  d.Kq.resize(body_.n());
  d.Dzd.resize(N);
  d.split.resize(2 * body_.n() + 2 * N);  // the split sums of the run-time-size kernel
  if (body_.geometric_stiffening()) {
    d.Hq.resize(body_.n());
    d.Hqd.resize(body_.n());
    d.Gq.resize(body_.n());
    d.Wv.resize(N);
  }
  return d;
}

void FullModel::bias(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::Ref<const Eigen::VectorXd>& zd,
                     Eigen::Ref<Eigen::VectorXd> out, Eigen::Ref<Eigen::VectorXd> Mq) const {
  const ModalIntegrals& mi = body_.integrals();
  const int n = body_.n();
  const double th = z(2), thd = zd(2);
  const auto q = z.tail(n);
  const auto qd = zd.tail(n);
  const Eigen::Matrix2d C = rot(th);
  if (body_.geometric_stiffening()) {
    // eq. 14.6: R row −θ'² C s + 2θ' C J B q' − C e1 (q'ᵀH̄q'); θ row 2θ' qᵀ(M − G_c)q';
    // q row −θ'² (M − G_c) q + K q, with s(q), B(q) of eq. 14.5
    const Eigen::VectorXd Hq = mi.H_bar * q;
    const Eigen::Vector2d s(mi.S_o - 0.5 * q.dot(Hq), mi.Phi_bar.dot(q));
    const Eigen::Vector2d Bqd(-Hq.dot(qd), mi.Phi_bar.dot(qd));
    Mq.noalias() = mi.M * q - mi.G_c * q;
    out.head<2>() = -thd * thd * (C * s) + 2.0 * thd * (C * kJ * Bqd) - qd.dot(mi.H_bar * qd) * C.col(0);
    out(2) = 2.0 * thd * Mq.dot(qd);
    out.tail(n) = -thd * thd * Mq + mi.K * q;
    if (body_.damped()) out.noalias() += body_.damping() * zd;
    return;
  }
  const Eigen::Vector2d s(mi.S_o, mi.Phi_bar.dot(q));
  const double Pqd = mi.Phi_bar.dot(qd);
  Mq.noalias() = mi.M * q;
  // eq. 6.2: R row -θ'² C s + 2θ' C J e2 Φ̄ q'; θ row 2θ' qᵀ M q'; q row -θ'² M q + K q
  out.head<2>() = -thd * thd * (C * s) + 2.0 * thd * Pqd * (C * kJ).col(1);
  out(2) = 2.0 * thd * Mq.dot(qd);
  out.tail(n) = -thd * thd * Mq + mi.K * q;
  if (body_.damped()) out.noalias() += body_.damping() * zd;
}

Eigen::VectorXd FullModel::residual(const Eigen::Ref<const Eigen::VectorXd>& z,
                                    const Eigen::Ref<const Eigen::VectorXd>& zd,
                                    const Eigen::Ref<const Eigen::VectorXd>& zdd,
                                    const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  const int N = body_.dofs(), n = body_.n();
  const Eigen::MatrixXd Mz = body_.mass_matrix(z(2), z.tail(n));
  Eigen::VectorXd h(N), Mq(n);
  bias(z, zd, h, Mq);
  const Eigen::VectorXd G = body_.generalized_force(z(2), z.tail(n), commands);
  return Mz * zdd + h - G;
}

namespace {

/// x, hidden from the optimizer: a product passed through it is rounded before any sum.
/// GCC matches the rotations below as complex products and, on a target with FMA (the
/// AVX-512 variant), fuses them into multiply-add/subtract whatever -ffp-contract says.
FREEFLEX_ALWAYS_INLINE double opaque(double x) {
#if defined(__x86_64__) && defined(__GNUC__)  // "x": an SSE register (the only target with that variant)
  __asm__("" : "+x"(x));
#endif
  return x;
}

#if defined(__GNUC__)
using util::load4;
using util::V4;
#endif

/// The body of FullModel::rhs for NN elastic coordinates known at compile time (NN > 0)
/// or at run time (NN = 0, n given). The same operations in the same order either way, so
/// the same bits with this file's flags (no contraction into fused multiply-adds, see
/// CMakeLists.txt) and no -march: a fixed NN only lets the compiler unroll and vectorize
/// the loops over entries (no reductions are reordered).
///
/// kSplit (the sizes without a kernel of their own, NOA 20 among them) sums in another
/// fixed order, with shorter chains of dependent additions, which bind the large sizes:
/// M q, K q and the elastic columns of 𝕄_b(0)⁻¹ g each as two interleaved halves added at
/// the end, and the four dot products four terms at a time. A different rounding from the
/// sequential order (tested to 1e-12 relative), and the same bits in every variant.
template <int NN, bool kSplit = false>
FREEFLEX_ALWAYS_INLINE bool full_rhs_kernel(const FlexibleBody& body, const Eigen::MatrixXd& rest_inverse, FullModel::Data& d,
                     const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& commands,
                     int n_runtime) {
  const ModalIntegrals& mi = body.integrals();
  const int n = NN > 0 ? NN : n_runtime, N = 3 + n;
  const double* z = x.data();
  const double* zd = z + N;
  const double* q = z + 3;
  const double* qd = zd + 3;
  const double th = z[2], thd = zd[2], thd2 = thd * thd;
  const double c = std::cos(th), s = std::sin(th);
  detail::generalized_force(body, th, x.segment(3, n), commands, d.G);  // R rows in inertial axes
  const double* G = d.G.data();
  // With the size known the sums run in local arrays, which the compiler keeps in registers
  // (through d's buffers it must store and reload them at every column: they might alias M).
  constexpr int kLocal = NN > 0 ? NN : 1;
  double Mq_local[kLocal], Kq_local[kLocal];
  double* Mq = NN > 0 ? Mq_local : d.Mq.data();
  double* Kq = NN > 0 ? Kq_local : d.Kq.data();
  // scratch of the split sums: on the stack for a fixed size, in the workspace otherwise
  double split_local[kSplit && NN > 0 ? 2 * NN + 2 * ((NN + 3 + 3) / 4 * 4) : 1];  // M q's halves, then g's
  double* split = NN > 0 ? split_local : d.split.data();
  if constexpr (kSplit) {
    const int h = n / 2;
    for (int pass = 0; pass < 2; ++pass) {  // M, then K
      const double* A = pass == 0 ? mi.M.data() : mi.K.data();
      double* out = pass == 0 ? Mq : Kq;
      double* lo = split;
      double* hi = split + n;
      for (int i = 0; i < n; ++i) lo[i] = hi[i] = 0.0;
      for (int k = 0; k < h; ++k) {
        const double* c1 = A + static_cast<std::ptrdiff_t>(k) * n;
        const double* c2 = A + static_cast<std::ptrdiff_t>(h + k) * n;
        const double q1 = q[k], q2 = q[h + k];
        for (int i = 0; i < n; ++i) {
          lo[i] += c1[i] * q1;
          hi[i] += c2[i] * q2;
        }
      }
      if (n % 2 == 1) {
        const double* c2 = A + static_cast<std::ptrdiff_t>(n - 1) * n;
        for (int i = 0; i < n; ++i) hi[i] += c2[i] * q[n - 1];
      }
      for (int i = 0; i < n; ++i) out[i] = lo[i] + hi[i];
    }
  } else {
    for (int i = 0; i < n; ++i) Mq[i] = Kq[i] = 0.0;
    for (int j = 0; j < n; ++j) {
      const double* Mc = mi.M.data() + static_cast<std::ptrdiff_t>(j) * n;
      const double* Kc = mi.K.data() + static_cast<std::ptrdiff_t>(j) * n;
      const double qj = q[j];
      for (int i = 0; i < n; ++i) {
        Mq[i] += Mc[i] * qj;
        Kq[i] += Kc[i] * qj;
      }
    }
  }
  double Pq = 0.0, Pqd = 0.0, qMq = 0.0, qMqd = 0.0;
  const double* Pb = mi.Phi_bar.data();
#if defined(__GNUC__)
  if constexpr (kSplit) {
    // each dot product four terms at a time, (s0 + s1) + (s2 + s3), then the rest in order
    V4 aP = {0.0, 0.0, 0.0, 0.0}, aPd = aP, aM = aP, aMd = aP;
    int i = 0;
    for (; i + 4 <= n; i += 4) {
      const V4 vq = load4(q + i), vqd = load4(qd + i), vP = load4(Pb + i), vM = load4(Mq + i);
      aP += vP * vq;
      aPd += vP * vqd;
      aM += vq * vM;
      aMd += vqd * vM;
    }
    Pq = (aP[0] + aP[1]) + (aP[2] + aP[3]);
    Pqd = (aPd[0] + aPd[1]) + (aPd[2] + aPd[3]);
    qMq = (aM[0] + aM[1]) + (aM[2] + aM[3]);
    qMqd = (aMd[0] + aMd[1]) + (aMd[2] + aMd[3]);
    for (; i < n; ++i) {
      Pq += Pb[i] * q[i];
      Pqd += Pb[i] * qd[i];
      qMq += q[i] * Mq[i];
      qMqd += qd[i] * Mq[i];
    }
  } else {
    // the four dot products as the lanes of one vector: each lane still sums its terms in
    // order (the same bits), one vector operation doing the work of four
    V4 acc = {0.0, 0.0, 0.0, 0.0};
    for (int i = 0; i < n; ++i) acc += V4{Pb[i], Pb[i], q[i], qd[i]} * V4{q[i], qd[i], Mq[i], Mq[i]};
    Pq = acc[0], Pqd = acc[1], qMq = acc[2], qMqd = acc[3];
  }
#else
  for (int i = 0; i < n; ++i) {
    Pq += Pb[i] * q[i];
    Pqd += Pb[i] * qd[i];
    qMq += q[i] * Mq[i];
    qMqd += qd[i] * Mq[i];
  }
#endif
  // g = Tᵀ (G − h − K q − D z'), eq. 6.2 with the R rows in body axes:
  // Cᵀ h_R = −θ'² (S_o, Φ̄ q) − 2θ' Φ̄ q' e_x; h_θ = 2θ' qᵀ M q'; h_q = −θ'² M q.
  double* g = d.b.data();
  g[0] = opaque(c * G[0]) + opaque(s * G[1]) + thd2 * mi.S_o + 2.0 * thd * Pqd;
  g[1] = opaque(-s * G[0]) + opaque(c * G[1]) + thd2 * Pq;
  g[2] = G[2] - 2.0 * thd * qMqd;
  for (int i = 0; i < n; ++i) g[3 + i] = G[3 + i] + thd2 * Mq[i] - Kq[i];
  if (body.damped()) {
    d.Dzd.noalias() = body.damping() * x.tail(N);
    const double* Dz = d.Dzd.data();
    g[0] -= opaque(c * Dz[0]) + opaque(s * Dz[1]);
    g[1] -= opaque(-s * Dz[0]) + opaque(c * Dz[1]);
    for (int i = 2; i < N; ++i) g[i] -= Dz[i];
  }
  // 𝕄_b (Tᵀ z'') = g with 𝕄_b = 𝕄_b(0) + U S Uᵀ, U = [e_x, e_θ], S = [[0, −Φ̄q], [−Φ̄q, qᵀMq]]:
  // w = y − W S (I + Uᵀ W S)⁻¹ Uᵀ y with y = 𝕄_b(0)⁻¹ g (no S⁻¹: S is singular at q = 0).
  // With the size known, the inverse comes with its columns padded to NP rows (zeros):
  // whole vectors only, and each of the first N sums the same terms in the same order.
  constexpr int NP = NN > 0 ? (NN + 3 + 3) / 4 * 4 : 1;
  const int ld = NN > 0 ? NP : N;  // rows of rest_inverse as stored
  assert(rest_inverse.rows() == ld);  // the padded inverse for a fixed size, the plain one otherwise
  Eigen::VectorXd& x_dot = d.x_dot;
  double w_local[NP];
  double* w = NN > 0 ? w_local : x_dot.data() + N;
  if constexpr (kSplit) {
    // the elastic columns as two interleaved halves (they wait only for M q and K q), the
    // three rigid ones (which wait for the dot products) apart; added at the end
    const int h = n / 2;
    double* lo = split + 2 * n;
    double* hi = lo + ld;
    for (int i = 0; i < ld; ++i) lo[i] = hi[i] = 0.0;
    for (int k = 0; k < h; ++k) {
      const int j1 = 3 + k, j2 = 3 + h + k;
      const double* c1 = rest_inverse.data() + static_cast<std::ptrdiff_t>(j1) * ld;
      const double* c2 = rest_inverse.data() + static_cast<std::ptrdiff_t>(j2) * ld;
      const double g1 = g[j1], g2 = g[j2];
      for (int i = 0; i < ld; ++i) {
        lo[i] += c1[i] * g1;
        hi[i] += c2[i] * g2;
      }
    }
    if (n % 2 == 1) {
      const double* c2 = rest_inverse.data() + static_cast<std::ptrdiff_t>(N - 1) * ld;
      for (int i = 0; i < ld; ++i) hi[i] += c2[i] * g[N - 1];
    }
    const double* c0 = rest_inverse.data();
    const double* c1 = c0 + ld;
    const double* c2 = c1 + ld;
    for (int i = 0; i < ld; ++i) w[i] = ((c0[i] * g[0] + c1[i] * g[1]) + c2[i] * g[2]) + (lo[i] + hi[i]);
  } else {
    for (int i = 0; i < ld; ++i) w[i] = 0.0;
    for (int j = 0; j < N; ++j) {
      const double* col = rest_inverse.data() + static_cast<std::ptrdiff_t>(j) * ld;
      const double gj = g[j];
      for (int i = 0; i < ld; ++i) w[i] += col[i] * gj;
    }
  }
  const double a = -Pq, cc = qMq;
  const double W00 = rest_inverse(0, 0), W01 = rest_inverse(0, 2), W20 = rest_inverse(2, 0),
               W21 = rest_inverse(2, 2);
  const double k00 = 1.0 + W01 * a, k01 = W00 * a + W01 * cc, k10 = W21 * a, k11 = 1.0 + W20 * a + W21 * cc;
  // det 𝕄_b = det 𝕄_b(0) · det(I + Uᵀ W S): a non-positive value means 𝕄 is not positive definite
  const double det = k00 * k11 - k01 * k10;
  if (!(det > 0.0)) return false;
  const double v0 = (k11 * w[0] - k01 * w[2]) / det, v1 = (k00 * w[2] - k10 * w[0]) / det;
  const double Sv0 = a * v1, Sv1 = a * v0 + cc * v1;
  const double* W0 = rest_inverse.data();
  const double* W2 = rest_inverse.data() + 2 * static_cast<std::ptrdiff_t>(ld);
  for (int i = 0; i < ld; ++i) w[i] -= W0[i] * Sv0 + W2[i] * Sv1;
  const double wx = w[0], wy = w[1];
  w[0] = opaque(c * wx) - opaque(s * wy);
  w[1] = opaque(s * wx) + opaque(c * wy);
  if (NN > 0) {
    double* out = x_dot.data() + N;
    for (int i = 0; i < N; ++i) out[i] = w[i];
  }
  for (int i = 0; i < N; ++i) x_dot[i] = zd[i];
  return true;
}

/// The sizes FullModel::rhs has a kernel of its own for (summing in sequential order).
constexpr bool has_own_kernel(int n) { return n == 4 || n == 6 || n == 8 || n == 10; }

}  // namespace

bool detail::full_rhs_runtime_size(const FullModel& model, FullModel::Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                                   const Eigen::Ref<const Eigen::VectorXd>& commands) {
  const int n = model.body().n();
  if (has_own_kernel(n))
    return full_rhs_kernel<0>(model.body(), model.rest_inverse(), d, x, commands, n);
  return full_rhs_kernel<0, true>(model.body(), model.rest_inverse(), d, x, commands, n);
}

bool detail::full_rhs_sequential(const FullModel& model, FullModel::Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                                 const Eigen::Ref<const Eigen::VectorXd>& commands) {
  return full_rhs_kernel<0>(model.body(), model.rest_inverse(), d, x, commands, model.body().n());
}

namespace {
// The kernels of NOA 20 and of the run-time size compiled twice, for AVX2 and for the
// baseline (util/avx2_clones.hpp; this file's -ffp-contract=off: the same bits). At NOA 20
// the right-hand side is bound by its arithmetic and runs 10-13% faster so
// (docs/benchmarks.md); at the small sizes the chain of dependent operations binds it and
// AVX2 did not pay (NOA 6: 2-3% slower), so those kernels stay as they are.
FREEFLEX_ALWAYS_INLINE bool large_kernels(const FlexibleBody& body, const Eigen::MatrixXd& rest_inverse,
                                          const Eigen::MatrixXd& rest_inverse_padded, FullModel::Data& d,
                                          const Eigen::Ref<const Eigen::VectorXd>& x,
                                          const Eigen::Ref<const Eigen::VectorXd>& commands) {
  if (body.n() == 20) return full_rhs_kernel<20, true>(body, rest_inverse_padded, d, x, commands, 20);
  return full_rhs_kernel<0, true>(body, rest_inverse, d, x, commands, body.n());
}
FREEFLEX_AVX2_CLONES bool large_rhs(const FlexibleBody& body, const Eigen::MatrixXd& rest_inverse,
                                   const Eigen::MatrixXd& rest_inverse_padded, FullModel::Data& d,
                                   const Eigen::Ref<const Eigen::VectorXd>& x,
                                   const Eigen::Ref<const Eigen::VectorXd>& commands) {
  return large_kernels(body, rest_inverse, rest_inverse_padded, d, x, commands);
}

// And a third time with 512-bit vectors where the processor has AVX-512: half the vector
// operations of AVX2, 7-16% less time at NOA 20 (docs/benchmarks.md). Still no fused
// multiply-add (AVX-512 implies FMA, so the rotations are kept from fusing by opaque()
// above), so the same bits as the other two (tested).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(_WIN32)  // GCC PR 54412
#define FF_FULL_AVX512 1
__attribute__((target("avx512f,avx512vl,prefer-vector-width=512"))) bool large_rhs_512(
    const FlexibleBody& body, const Eigen::MatrixXd& rest_inverse, const Eigen::MatrixXd& rest_inverse_padded,
    FullModel::Data& d, const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& commands) {
  return large_kernels(body, rest_inverse, rest_inverse_padded, d, x, commands);
}
#else
#define FF_FULL_AVX512 0
#endif
}  // namespace

bool detail::full_rhs_avx512_available() {
#if FF_FULL_AVX512
  static const bool ok = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl");
  return ok;
#else
  return false;
#endif
}

bool detail::full_rhs_large(const FullModel& model, FullModel::Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                            const Eigen::Ref<const Eigen::VectorXd>& commands, bool avx512) {
#if FF_FULL_AVX512
  if (avx512 && full_rhs_avx512_available())
    return large_rhs_512(model.body(), model.rest_inverse(), model.rest_inverse_padded(), d, x, commands);
#else
  (void)avx512;
#endif
  return large_rhs(model.body(), model.rest_inverse(), model.rest_inverse_padded(), d, x, commands);
}

bool FullModel::rhs(Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                    const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  if (body_.geometric_stiffening()) return rhs_stiffened(d, x, commands);
  // The equations of residual(), written as plain loops over raw arrays: this runs tens of
  // thousands of times per simulation on vectors of 9 to 30 entries, where the setup of
  // Eigen's dynamic-size kernels costs more than the arithmetic. The common sizes get a
  // kernel of their own (NOA 6, the paper's, took 1 516 instructions a call at run-time
  // size; docs/benchmarks.md).
  if (!has_own_kernel(body_.n())) return detail::full_rhs_large(*this, d, x, commands, true);
  switch (body_.n()) {
    case 4: return full_rhs_kernel<4>(body_, rest_inverse_padded_, d, x, commands, 4);
    case 6: return full_rhs_kernel<6>(body_, rest_inverse_padded_, d, x, commands, 6);
    case 8: return full_rhs_kernel<8>(body_, rest_inverse_padded_, d, x, commands, 8);
    default: return full_rhs_kernel<10>(body_, rest_inverse_padded_, d, x, commands, 10);
  }
}

bool FullModel::rhs_stiffened(Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  // eq. 14.6 in body axes, solved by the kept inverse of 𝕄_b(0) and a 4 x 4 Woodbury core.
  const ModalIntegrals& mi = body_.integrals();
  const int N = body_.dofs(), n = body_.n();
  const auto q = x.segment(3, n);
  const auto qd = x.segment(N + 3, n);
  const double th = x(2), thd = x(N + 2), thd2 = thd * thd;
  const double c = std::cos(th), s = std::sin(th);
  detail::generalized_force(body_, th, q, commands, d.G);  // R rows in inertial axes
  d.Hq.noalias() = mi.H_bar * q;
  d.Hqd.noalias() = mi.H_bar * qd;
  d.Mq.noalias() = mi.M * q;
  d.Gq.noalias() = mi.G_c * q;
  d.Mq -= d.Gq;  // (M − G_c) q
  d.Kq.noalias() = mi.K * q;
  const double Pq = mi.Phi_bar.dot(q), Pqd = mi.Phi_bar.dot(qd);
  const double qHq = q.dot(d.Hq), qdHq = qd.dot(d.Hq), qdHqd = qd.dot(d.Hqd);
  const double sx = mi.S_o - 0.5 * qHq, sy = Pq;
  const double qMq = q.dot(d.Mq), qMqd = qd.dot(d.Mq);
  // g = Tᵀ (G − h − K q − D z') with Cᵀ h_R = −θ'² s + 2θ' J B q' − e1 q'ᵀH̄q',
  // J B q' = [−Φ̄q', −qᵀH̄q']; h_θ = 2θ' qᵀ(M − G_c)q'; h_q = −θ'² (M − G_c) q
  Eigen::VectorXd& g = d.b;
  const double* G = d.G.data();
  g(0) = c * G[0] + s * G[1] + thd2 * sx + 2.0 * thd * Pqd + qdHqd;
  g(1) = -s * G[0] + c * G[1] + thd2 * sy + 2.0 * thd * qdHq;
  g(2) = G[2] - 2.0 * thd * qMqd;
  g.tail(n) = d.G.tail(n) + thd2 * d.Mq - d.Kq;
  if (body_.damped()) {
    d.Dzd.noalias() = body_.damping() * x.tail(N);
    g(0) -= c * d.Dzd(0) + s * d.Dzd(1);
    g(1) -= -s * d.Dzd(0) + c * d.Dzd(1);
    g.tail(N - 2) -= d.Dzd.tail(N - 2);
  }
  // 𝕄_b(q) = 𝕄_b(0) + U S Uᵀ with U = [e_x, e_y, e_θ, v], v = [0; 0; 0; H̄q] and
  // S(x,θ) = −Φ̄q, S(y,θ) = −½ qᵀH̄q, S(θ,θ) = qᵀ(M − G_c)q, S(x,v) = −1 (eq. 14.5):
  // w = y − W U S (I + Uᵀ W U S)⁻¹ Uᵀ y, y = W g, W = 𝕄_b(0)⁻¹.
  const Eigen::MatrixXd& W = rest_inverse_;
  Eigen::VectorXd& x_dot = d.x_dot;
  auto w = x_dot.tail(N);
  w.noalias() = W * g;
  d.Wv.noalias() = W.rightCols(n) * d.Hq;
  Eigen::Matrix<double, Eigen::Dynamic, 4> WU(N, 4);
  WU.col(0) = W.col(0);
  WU.col(1) = W.col(1);
  WU.col(2) = W.col(2);
  WU.col(3) = d.Wv;
  if (!detail::stiffened_correction(x_dot, WU, d.Wv, d.Hq, Pq, qHq, qMq, c, s)) return false;
  x_dot.head(N) = x.tail(N);
  return true;
}

bool detail::stiffened_correction(Eigen::VectorXd& x_dot, const Eigen::Matrix<double, Eigen::Dynamic, 4>& WU,
                                  const Eigen::VectorXd& Wv, const Eigen::VectorXd& Hq, double Pq, double qHq,
                                  double qMq, double c, double s) {
  const int n = static_cast<int>(Hq.size()), N = 3 + n;
  auto w = x_dot.tail(N);
  Eigen::Matrix4d UWU;
  UWU.topLeftCorner<3, 3>() = WU.topLeftCorner<3, 3>();
  UWU.block<3, 1>(0, 3) = Wv.head<3>();
  UWU.block<1, 3>(3, 0) = Wv.head<3>().transpose();
  UWU(3, 3) = Hq.dot(Wv.tail(n));
  Eigen::Matrix4d S = Eigen::Matrix4d::Zero();
  S(0, 2) = S(2, 0) = -Pq;
  S(1, 2) = S(2, 1) = -0.5 * qHq;
  S(2, 2) = qMq;
  S(0, 3) = S(3, 0) = -1.0;
  const Eigen::Matrix4d core = Eigen::Matrix4d::Identity() + UWU * S;
  // det 𝕄_b = det 𝕄_b(0) · det(core): a non-positive value means 𝕄 is not positive
  // definite. The kinetic energy is kept to second order in q: once 𝕄_b(q) has lost all
  // but kMinMassDeterminantRatio of the determinant at rest, the dropped higher-order terms
  // are of the size of what is left (a frame whose own rotary inertia the bending has used
  // up, say); the accelerations grow without bound as det → 0 and the state is out of the
  // model's range.
  const double det = core.determinant();
  if (!(det > kMinMassDeterminantRatio)) return false;
  const Eigen::Vector4d Uy(w(0), w(1), w(2), Hq.dot(w.tail(n)));
  const Eigen::Vector4d zc = S * core.partialPivLu().solve(Uy);
  w.noalias() -= WU * zc;
  const double wx = w(0), wy = w(1);
  w(0) = c * wx - s * wy;
  w(1) = s * wx + c * wy;
  return true;
}

bool FullModel::prescribed_rhs(Data& d, const RigidState& rigid, const Eigen::Ref<const Eigen::VectorXd>& xq,
                               const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  const ModalIntegrals& mi = body_.integrals();
  const int n = body_.n(), N = body_.dofs();
  const auto q = xq.head(n);
  const auto qd = xq.tail(n);
  const double th = rigid.pos(2), thd = rigid.vel(2), thdd = rigid.acc(2);
  const Eigen::Matrix2d C = rot(th);
  const Eigen::Vector2d a = C.transpose() * rigid.acc.head<2>();  // R'' in body axes
  detail::generalized_force(body_, th, q, commands, d.G);
  // eq. 14.10: f = Q − Φ̄ᵀ a_y + a_x H̄ q − Φ̃ᵀ θ'' + θ'² (M − G_c) q − K q − D_q z'
  auto f = d.b.tail(n);
  f = d.G.tail(n) - a(1) * mi.Phi_bar.transpose() - thdd * mi.Phi_tilde.transpose();
  d.Mq.noalias() = mi.M * q;
  if (body_.geometric_stiffening()) {
    d.Mq.noalias() -= mi.G_c * q;
    f.noalias() += a(0) * (mi.H_bar * q);
  }
  f += (thd * thd) * d.Mq;
  f.noalias() -= mi.K * q;
  if (body_.damped()) {
    d.zd_full.resize(N);
    d.zd_full.head<3>() = rigid.vel;
    d.zd_full.tail(n) = qd;
    f.noalias() -= body_.damping().bottomRows(n) * d.zd_full;
  }
  d.xq_dot.resize(2 * n);
  d.xq_dot.head(n) = qd;
  d.xq_dot.tail(n).noalias() = mq_inverse_ * f;
  return true;
}

Eigen::Vector3d FullModel::constraint_force(const Eigen::Ref<const Eigen::VectorXd>& z,
                                            const Eigen::Ref<const Eigen::VectorXd>& zd,
                                            const Eigen::Ref<const Eigen::VectorXd>& zdd,
                                            const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  return residual(z, zd, zdd, commands).head<3>();
}

double FullModel::energy(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const int N = body_.dofs(), n = body_.n();
  const Eigen::MatrixXd Mz = body_.mass_matrix(x(2), x.segment(3, n));
  const auto zd = x.tail(N);
  const auto q = x.segment(3, n);
  return 0.5 * zd.dot(Mz * zd) + 0.5 * q.dot(body_.integrals().K * q);
}

Eigen::Vector2d FullModel::linear_momentum(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const ModalIntegrals& mi = body_.integrals();
  const int N = body_.dofs(), n = body_.n();
  const Eigen::Matrix2d C = rot(x(2));
  if (body_.geometric_stiffening()) {
    // ∂T/∂R' = m R' + C (θ' J s(q) + B(q) q'), eq. 14.8
    const auto q = x.segment(3, n);
    const auto qd = x.tail(n);
    const Eigen::VectorXd Hq = mi.H_bar * q;
    const Eigen::Vector2d s(mi.S_o - 0.5 * q.dot(Hq), mi.Phi_bar.dot(q));
    const Eigen::Vector2d Bqd(-Hq.dot(qd), mi.Phi_bar.dot(qd));
    return mi.m * x.segment<2>(N) + C * (x(N + 2) * (kJ * s) + Bqd);
  }
  const Eigen::Vector2d s(mi.S_o, mi.Phi_bar.dot(x.segment(3, n)));
  const auto zd = x.tail(N);
  // ∂T/∂R' = m R' + C (θ' J s + e2 Φ̄ q')
  return mi.m * zd.head<2>() + C * (zd(2) * (kJ * s) + Eigen::Vector2d(0.0, mi.Phi_bar.dot(zd.tail(n))));
}

double FullModel::angular_momentum(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const ModalIntegrals& mi = body_.integrals();
  const int N = body_.dofs(), n = body_.n();
  const Eigen::Matrix2d C = rot(x(2));
  const auto q = x.segment(3, n);
  const auto zd = x.tail(N);
  const Eigen::Vector2d R = x.head<2>(), Rd = zd.head<2>();
  const Eigen::Vector2d s(mi.S_o, mi.Phi_bar.dot(q));
  const double thd = zd(2);
  const double Pqd = mi.Phi_bar.dot(zd.tail(n));
  // H = ∫ (r × r') dm with r = R + C p (eq. 6.7); a × b = aᵀ Jᵀ b in the plane.
  auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a(0) * b(1) - a(1) * b(0); };
  if (body_.geometric_stiffening()) {
    // eq. 14.8: H = R × P + (C s) × R' + θ' I(q) + Φ̃ q', P the linear momentum
    const Eigen::VectorXd Hq = mi.H_bar * q;
    const Eigen::Vector2d ss(mi.S_o - 0.5 * q.dot(Hq), mi.Phi_bar.dot(q));
    const double Iq = mi.I_o + q.dot((mi.M - mi.G_c) * q);
    return cross(R, linear_momentum(x)) + cross(C * ss, Rd) + thd * Iq + mi.Phi_tilde.dot(zd.tail(n));
  }
  return mi.m * cross(R, Rd) + thd * R.dot(C * s) + cross(R, C.col(1)) * Pqd + cross(C * s, Rd) +
         thd * (mi.I_o + q.dot(mi.M * q)) + mi.Phi_tilde.dot(zd.tail(n));
}

}  // namespace freeflex
