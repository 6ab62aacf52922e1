// The full model in rest-mode coordinates (rest_mode_model.hpp).
#include "dynamics/rest_mode_model.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "dynamics/full_model_kernel.hpp"
#include "util/vec4.hpp"

namespace freeflex::detail {

using util::V4;
using util::load4;
using util::splat4;
using util::store4;

RestModeModel::RestModeModel(const FlexibleBody& body, bool dense_damping) : body_(body), n_(body.n()) {
  const RestModes modes = rest_modes(body);
  // Ψ scaled to Ψᵀ M_c Ψ = μ I with μ the mean diagonal of M, so that η is of the size of
  // q (for M = μ I and no rigid coupling, Ψ would be orthogonal) and the integrator's
  // tolerances mean in η what they mean in q, whatever the beam's mass
  mu_ = body.integrals().M.trace() / n_;
  Psi_ = modes.Phi * std::sqrt(mu_);
  Psi_inverse_ = Psi_.transpose() * modes.M_c / mu_;
  L_ = mu_ * modes.omega2;
  const Eigen::MatrixXd M0 = body.mass_matrix(0.0, Eigen::VectorXd::Zero(n_));
  const Eigen::Matrix3d A = M0.topLeftCorner<3, 3>();
  A_inverse_ = A.ldlt().solve(Eigen::Matrix3d::Identity());
  if (!M0.block(0, 3, 1, n_).isZero(0.0))
    throw std::logic_error("rest-mode coordinates: the body-frame mass matrix couples x with q at rest (eq. 6.1 has no such entry)");
  B_y_ = (M0.block(1, 3, 1, n_) * Psi_).transpose();
  B_theta_ = (M0.block(2, 3, 1, n_) * Psi_).transpose();
  S_o_ = body.integrals().S_o;
  const int N = 3 + n_;
  // the Woodbury columns 𝕄_η(0)⁻¹ e_x, e_y, e_θ
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(N, 3);
  W_x_.resize(N);
  W_y_.resize(N);
  W_theta_.resize(N);
  rest_solve(I.col(0), W_x_);
  rest_solve(I.col(1), W_y_);
  rest_solve(I.col(2), W_theta_);
  if (body.damped()) {
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(N, N);
    S.topLeftCorner<3, 3>().setIdentity();
    S.bottomRightCorner(n_, n_) = Psi_;
    D_ = S.transpose() * body.damping() * S;
    // The modal damping (eq. 6.5) is diagonal in the modes at rest and leaves the rigid
    // rows alone; then the kernel applies its diagonal. Off the diagonal stands round-off
    // of the two eigensolvers (D is formed from the modes of the whole body, Ψ from those
    // of q with the rigid momenta held): up to 2.4e-10 of the largest entry at NOA 60
    // with o at the root, so entries below 1e-8 of it are taken as zero (a change of the
    // damping force by 1e-8 of itself at most). Two modes of one frequency with different
    // ratios could come out rotated against each other: the full product then.
    const Eigen::VectorXd dd = D_.diagonal().tail(n_);
    Eigen::MatrixXd off = D_;
    off.diagonal().tail(n_).setZero();
    if (!dense_damping && off.cwiseAbs().maxCoeff() <= 1e-8 * dd.cwiseAbs().maxCoeff()) damping_diagonal_ = dd;
  }
  if (body.geometric_stiffening()) {
    H_ = Psi_.transpose() * body.integrals().H_bar * Psi_;
    G_c_ = Psi_.transpose() * body.integrals().G_c * Psi_;
  }
  rows_ = ElementRows(body, Psi_);
}

void RestModeModel::rest_solve(const Eigen::Ref<const Eigen::VectorXd>& g, Eigen::Ref<Eigen::VectorXd> y) const {
  // u = A⁻¹ g_r; y_η = (g_η − Bᵀ u) / μ; y_r = u − A⁻¹ B y_η (B's x row is zero)
  const Eigen::Vector3d u = A_inverse_ * g.head<3>();
  y.tail(n_) = (g.tail(n_) - (B_y_ * u(1) + B_theta_ * u(2))) * (1.0 / mu_);
  y.head<3>() = u - A_inverse_ * Eigen::Vector3d(0.0, B_y_.dot(y.tail(n_)), B_theta_.dot(y.tail(n_)));
}

double RestModeModel::damping_power(const Eigen::Ref<const Eigen::VectorXd>& y_dot_z) const {
  if (!body_.damped()) return 0.0;
  if (damping_diagonal_.size()) return y_dot_z.tail(n_).dot(damping_diagonal_.cwiseProduct(y_dot_z.tail(n_)));
  return y_dot_z.dot(D_ * y_dot_z);
}

RestModeModel::Data RestModeModel::create_data() const {
  const int N = 3 + n_;
  Data d;
  d.x_dot.resize(2 * N);
  d.G.resize(N);
  d.g.resize(N);
  d.Dzd.resize(N);
  if (body_.geometric_stiffening()) {
    d.Hq.resize(n_);
    d.Hqd.resize(n_);
    d.Mq.resize(n_);
    d.Wv.resize(N);
    d.v = Eigen::VectorXd::Zero(N);
    d.WU.resize(N, 4);
    d.WU.col(0) = W_x_;
    d.WU.col(1) = W_y_;
    d.WU.col(2) = W_theta_;
  }
  return d;
}

Eigen::VectorXd RestModeModel::to_rest_modes(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const int N = 3 + n_;
  Eigen::VectorXd y = x;
  y.segment(3, n_) = Psi_inverse_ * x.segment(3, n_);
  y.segment(N + 3, n_) = Psi_inverse_ * x.segment(N + 3, n_);
  return y;
}

void RestModeModel::to_physical(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> x) const {
  const int N = 3 + n_;
  x = y;
  x.segment(3, n_).noalias() = Psi_ * y.segment(3, n_);
  x.segment(N + 3, n_).noalias() = Psi_ * y.segment(N + 3, n_);
}

void RestModeModel::generalized_force(double theta, const Eigen::Ref<const Eigen::VectorXd>& eta,
                                      const Eigen::Ref<const Eigen::VectorXd>& commands,
                                      Eigen::Ref<Eigen::VectorXd> G) const {
  detail::generalized_force(body_, rows_, theta, eta, commands, G);
}

namespace {

/// What rest_mode_kernel reads besides the state.
struct KernelData {
  int n;
  const double* G;   ///< generalized force, R rows inertial
  const double* d;   ///< the diagonal of the elastic damping, or null
  const double* Dz;  ///< D ż with a damping that is not diagonal, or null
  const double *By, *Bt, *L, *Wx, *Wt, *Ai;  ///< B's y and θ rows, μΛ, Woodbury columns, A⁻¹ (column-major)
  double mu, S_o;
};

enum Damping { kUndamped, kDiagonal, kDense };

/// The arithmetic of rhs() on raw arrays, in three passes over the n elastic entries, four
/// at a time (fixed lanes, so the same bits in every variant: this file is built without
/// fused multiply-adds); compiled once per kind of damping.
template <Damping kDamping>
FREEFLEX_ALWAYS_INLINE bool rest_mode_kernel(const KernelData& k, const double* x, double* out) {
  const int n = k.n, N = 3 + n;
  const double *G = k.G, *By = k.By, *Bt = k.Bt, *L = k.L, *Ai = k.Ai, *dg = k.d, *Dz = k.Dz;
  const double mu = k.mu;
  const double* z = x;
  const double* zd = x + N;
  const double* eta = z + 3;
  const double* etad = zd + 3;
  const double th = z[2], thd = zd[2], thd2 = thd * thd;
  const double c = std::cos(th), s = std::sin(th);
  // 1. b = B η, b' = B η' (b_y = Φ̄ q, b_θ = Φ̃ q), ηᵀη, ηᵀη'
  V4 a1 = splat4(0.0), a2 = a1, ad1 = a1, ad2 = a1, aee = a1, aeed = a1;
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    const V4 e = load4(eta + i), ed = load4(etad + i), y = load4(By + i), t = load4(Bt + i);
    a1 += y * e;
    a2 += t * e;
    ad1 += y * ed;
    ad2 += t * ed;
    aee += e * e;
    aeed += e * ed;
  }
  double b1 = util::lane_sum(a1), b2 = util::lane_sum(a2), bd1 = util::lane_sum(ad1), bd2 = util::lane_sum(ad2),
         ee = util::lane_sum(aee), eed = util::lane_sum(aeed);
  for (; i < n; ++i) {
    b1 += By[i] * eta[i];
    b2 += Bt[i] * eta[i];
    bd1 += By[i] * etad[i];
    bd2 += Bt[i] * etad[i];
    ee += eta[i] * eta[i];
    eed += eta[i] * etad[i];
  }
  // Ψᵀ M q = μ η + Bᵀ a with a = A⁻¹ b (b_x = 0); qᵀ M q = μ ηᵀη + bᵀ a; qᵀ M q' = μ ηᵀη' + b'ᵀ a
  const double ay = Ai[4] * b1 + Ai[7] * b2, at = Ai[5] * b1 + Ai[8] * b2;  // a_x enters nothing
  const double qMq = mu * ee + (b1 * ay + b2 * at), qMqd = mu * eed + (bd1 * ay + bd2 * at);
  const double Pq = b1, Pqd = bd1;  // B's y row is Φ̄ Ψ
  // 2. g = Tᵀ (G − h − K q − D z') as FullModel::rhs, the elastic rows projected on Ψ, and
  // y = 𝕄_η(0)⁻¹ g by the block inverse: u = A⁻¹ g_r, y_η = (g_η − Bᵀ u) / μ, y_r = u − A⁻¹ B y_η
  double gr0 = c * G[0] + s * G[1] + thd2 * k.S_o + 2.0 * thd * Pqd;
  double gr1 = -s * G[0] + c * G[1] + thd2 * Pq;
  double gr2 = G[2] - 2.0 * thd * qMqd;
  if (kDamping == kDense) {  // a damping that is not diagonal (the diagonal one leaves the rigid rows alone)
    gr0 -= c * Dz[0] + s * Dz[1];
    gr1 -= -s * Dz[0] + c * Dz[1];
    gr2 -= Dz[2];
  }
  const double u0 = Ai[0] * gr0 + Ai[3] * gr1 + Ai[6] * gr2, u1 = Ai[1] * gr0 + Ai[4] * gr1 + Ai[7] * gr2,
               u2 = Ai[2] * gr0 + Ai[5] * gr1 + Ai[8] * gr2;
  // μ y_η,i = G_i + (θ'² μ − μλ_i) η_i + B_y,i (θ'² a_y − u_y) + B_θ,i (θ'² a_θ − u_θ) − (D ż)_i
  const double cy = thd2 * ay - u1, ct = thd2 * at - u2, cm = thd2 * mu, inv_mu = 1.0 / mu;
  double* w = out + N;  // z'' (body axes until the end)
  V4 sy = splat4(0.0), st = sy;
  const V4 vcm = splat4(cm), vcy = splat4(cy), vct = splat4(ct), vinv = splat4(inv_mu);
  i = 0;
  for (; i + 4 <= n; i += 4) {
    const V4 y = load4(By + i), t = load4(Bt + i);
    V4 v = load4(G + 3 + i) + (vcm - load4(L + i)) * load4(eta + i) + (y * vcy + t * vct);
    if (kDamping == kDiagonal) v = v - load4(dg + i) * load4(etad + i);
    if (kDamping == kDense) v = v - load4(Dz + 3 + i);
    v = v * vinv;
    store4(w + 3 + i, v);
    sy += y * v;
    st += t * v;
  }
  double By_y = util::lane_sum(sy), Bt_y = util::lane_sum(st);
  for (; i < n; ++i) {
    double v = G[3 + i] + (cm - L[i]) * eta[i] + (By[i] * cy + Bt[i] * ct);
    if (kDamping == kDiagonal) v -= dg[i] * etad[i];
    if (kDamping == kDense) v -= Dz[3 + i];
    v *= inv_mu;
    w[3 + i] = v;
    By_y += By[i] * v;
    Bt_y += Bt[i] * v;
  }
  w[0] = u0 - (Ai[3] * By_y + Ai[6] * Bt_y);
  w[1] = u1 - (Ai[4] * By_y + Ai[7] * Bt_y);
  w[2] = u2 - (Ai[5] * By_y + Ai[8] * Bt_y);
  // 3. 𝕄_b(q) = 𝕄_b(0) + U S Uᵀ, U = [e_x, e_θ], S = [[0, −Φ̄q], [−Φ̄q, qᵀMq]]: the rigid
  // entries only, the same in any elastic coordinates (FullModel::rhs), by Woodbury
  const double* Wx = k.Wx;
  const double* Wt = k.Wt;
  const double aa = -Pq, cc = qMq;
  const double W00 = Wx[0], W01 = Wt[0], W20 = Wx[2], W21 = Wt[2];
  const double k00 = 1.0 + W01 * aa, k01 = W00 * aa + W01 * cc, k10 = W21 * aa, k11 = 1.0 + W20 * aa + W21 * cc;
  const double det = k00 * k11 - k01 * k10;  // det 𝕄_b(q) / det 𝕄_b(0)
  if (!(det > 0.0)) return false;
  const double v0 = (k11 * w[0] - k01 * w[2]) / det, v1 = (k00 * w[2] - k10 * w[0]) / det;
  const double Sv0 = aa * v1, Sv1 = aa * v0 + cc * v1;
  const V4 vS0 = splat4(Sv0), vS1 = splat4(Sv1);
  i = 0;
  for (; i + 4 <= N; i += 4) store4(w + i, load4(w + i) - (load4(Wx + i) * vS0 + load4(Wt + i) * vS1));
  for (; i < N; ++i) w[i] -= Wx[i] * Sv0 + Wt[i] * Sv1;
  const double wx = w[0], wy = w[1];
  w[0] = c * wx - s * wy;
  w[1] = s * wx + c * wy;
  std::memcpy(out, zd, sizeof(double) * N);
  return true;
}

FREEFLEX_AVX2_CLONES bool rest_mode_kernels(const KernelData& k, const double* x, double* out) {
  if (k.d) return rest_mode_kernel<kDiagonal>(k, x, out);
  if (k.Dz) return rest_mode_kernel<kDense>(k, x, out);
  return rest_mode_kernel<kUndamped>(k, x, out);
}

}  // namespace

bool rest_mode_rhs(const RestModeModel& m, RestModeModel::Data& d, const double* x,
                   const Eigen::Ref<const Eigen::VectorXd>& commands) {
  const int n = m.n_, N = 3 + n;
  m.generalized_force(x[2], Eigen::Map<const Eigen::VectorXd>(x + 3, n), commands, d.G);
  KernelData k{n,       d.G.data(),          nullptr,         nullptr,     m.B_y_.data(), m.B_theta_.data(),
               m.L_.data(), m.W_x_.data(), m.W_theta_.data(), m.A_inverse_.data(), m.mu_, m.S_o_};
  if (m.damping_diagonal_.size()) {
    k.d = m.damping_diagonal_.data();
  } else if (m.body_.damped()) {
    d.Dzd.noalias() = m.D_ * Eigen::Map<const Eigen::VectorXd>(x + N, N);
    k.Dz = d.Dzd.data();
  }
  return rest_mode_kernels(k, x, d.x_dot.data());
}

bool RestModeModel::rhs(Data& d, const Eigen::Ref<const Eigen::VectorXd>& y,
                        const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  if (body_.geometric_stiffening()) return rhs_stiffened(d, y, commands);
  return rest_mode_rhs(*this, d, y.data(), commands);
}

bool RestModeModel::rhs_stiffened(Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                                  const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  // FullModel::rhs_stiffened term by term, with Ψᵀ (M − G_c) Ψ η = μ η + Bᵀ A⁻¹ B η − G̃_c η,
  // Ψᵀ K Ψ η = μ Λ η and the solves with 𝕄_η(0) by its block inverse
  const int N = 3 + n_, n = n_;
  const auto eta = x.segment(3, n);
  const auto etad = x.segment(N + 3, n);
  const double th = x(2), thd = x(N + 2), thd2 = thd * thd;
  const double c = std::cos(th), s = std::sin(th);
  generalized_force(th, eta, commands, d.G);  // R rows in inertial axes
  d.Hq.noalias() = H_ * eta;
  d.Hqd.noalias() = H_ * etad;
  const double Pq = B_y_.dot(eta), Pqd = B_y_.dot(etad);
  const Eigen::Vector3d a = A_inverse_ * Eigen::Vector3d(0.0, Pq, B_theta_.dot(eta));
  d.Mq.noalias() = mu_ * eta + B_y_ * a(1) + B_theta_ * a(2) - G_c_ * eta;  // Ψᵀ (M − G_c) q
  const double qHq = eta.dot(d.Hq), qdHq = etad.dot(d.Hq), qdHqd = etad.dot(d.Hqd);
  const double sx = S_o_ - 0.5 * qHq, sy = Pq;
  const double qMq = eta.dot(d.Mq), qMqd = etad.dot(d.Mq);
  Eigen::VectorXd& g = d.g;
  const double* G = d.G.data();
  g(0) = c * G[0] + s * G[1] + thd2 * sx + 2.0 * thd * Pqd + qdHqd;
  g(1) = -s * G[0] + c * G[1] + thd2 * sy + 2.0 * thd * qdHq;
  g(2) = G[2] - 2.0 * thd * qMqd;
  g.tail(n) = d.G.tail(n) + thd2 * d.Mq - L_.cwiseProduct(eta);
  if (damping_diagonal_.size()) {
    g.tail(n) -= damping_diagonal_.cwiseProduct(etad);
  } else if (body_.damped()) {
    d.Dzd.noalias() = D_ * x.tail(N);
    g(0) -= c * d.Dzd(0) + s * d.Dzd(1);
    g(1) -= -s * d.Dzd(0) + c * d.Dzd(1);
    g.tail(N - 2) -= d.Dzd.tail(N - 2);
  }
  // 𝕄_b(q) = 𝕄_b(0) + U S Uᵀ, U = [e_x, e_y, e_θ, v], v = [0; 0; 0; H̄q] (eq. 14.5):
  // the columns 𝕄_η(0)⁻¹ U by the block inverse, then FullModel's correction
  auto w = d.x_dot.tail(N);
  rest_solve(g, w);
  d.v.tail(n) = d.Hq;  // its head stays zero
  rest_solve(d.v, d.Wv);
  d.WU.col(3) = d.Wv;  // the first three columns are set by create_data()
  if (!stiffened_correction(d.x_dot, d.WU, d.Wv, d.Hq, Pq, qHq, qMq, c, s)) return false;
  d.x_dot.head(N) = x.tail(N);
  return true;
}

}  // namespace freeflex::detail
