// The first-order elastic motion inside the maneuver optimizer (trajopt/elastic_dynamics.hpp):
// the feature matrices P_i, c_i formed once from the body, and their contractions.
#include "freeflex/trajopt/elastic_dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace freeflex {

namespace {

Eigen::Matrix2d rot(double theta) {
  Eigen::Matrix2d C;
  C << std::cos(theta), -std::sin(theta), std::sin(theta), std::cos(theta);
  return C;
}

}  // namespace

ElasticDynamics::ElasticDynamics(const FlexibleBody& body, std::vector<int> actuators, int modes)
    : ElasticDynamics(body, std::move(actuators), Stiffening{body.integrals().H_bar, body.integrals().G_c}, modes) {}

ElasticDynamics::ElasticDynamics(const FlexibleBody& body, std::vector<int> actuators, const Stiffening& stiffening,
                                 int modes)
    : modes_(modes), actuators_(std::move(actuators)) {
  const RigidDynamics check(body, actuators_);  // the same actuator checks and messages
  n_ = body.n();
  if (modes != all_modes && (modes < 1 || modes > n_))
    throw std::invalid_argument("elastic dynamics: modes = " + std::to_string(modes) + ", expected 1 .. " +
                                std::to_string(n_) + " (the body's elastic coordinates) or all_modes (-1)");
  truncated_ = modes != all_modes;
  m_ = truncated_ ? modes : n_;
  nu_ = static_cast<int>(actuators_.size());
  na_ = 3 + m_;
  if (stiffening.H_bar.rows() != n_ || stiffening.H_bar.cols() != n_ || stiffening.G_c.rows() != n_ ||
      stiffening.G_c.cols() != n_)
    throw std::invalid_argument("elastic dynamics: stiffening H_bar and G_c must be " + std::to_string(n_) + " x " +
                                std::to_string(n_));
  build(body, stiffening);
}

void ElasticDynamics::build(const FlexibleBody& body, const Stiffening& stiff) {
  const ModalIntegrals& mi = body.integrals();
  const int n = n_, N = 3 + n_, nr = na_, nx1 = nx();
  const double m = mi.m, S = mi.S_o, D = mi.I_o - S * S / m;
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(n);
  Mb_ = body.mass_matrix(0.0, q0);  // 𝕄 at rest in body axes: constant (eq. 11.4)
  // Elastic modes at rest, mass-normalized (eq. 4.1): 𝕄_b v is zero in its rigid rows,
  // and its q rows give η = vᵀ 𝕄_b δz = (M_c φ)ᵀ q.
  Eigen::MatrixXd K0 = Eigen::MatrixXd::Zero(N, N);
  K0.bottomRightCorner(n, n) = mi.K;
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K0, Mb_);
  V_ = es.eigenvectors().rightCols(n);
  const Eigen::VectorXd omega_all = es.eigenvalues().tail(n).cwiseMax(0.0).cwiseSqrt();
  const Eigen::MatrixXd rows_all = (Mb_ * V_).bottomRows(n).transpose();  // η = rows_all q
  // The coordinates of x1: q itself, or the first m modes (q = B ξ, a Galerkin projection).
  B_ = truncated_ ? Eigen::MatrixXd(V_.bottomRows(n).leftCols(m_)) : Eigen::MatrixXd::Identity(n, n);
  Eigen::MatrixXd TN = Eigen::MatrixXd::Zero(N, nr), Tpos = Eigen::MatrixXd::Zero(1 + n, 1 + m_);
  TN.topLeftCorner<3, 3>().setIdentity();
  TN.bottomRightCorner(n, m_) = B_;
  Tpos(0, 0) = 1.0;
  Tpos.bottomRightCorner(n, m_) = B_;
  const Eigen::LDLT<Eigen::MatrixXd> Mb_ldlt(TN.transpose() * Mb_ * TN);
  Eigen::Matrix2d J;
  J << 0, -1, 1, 0;
  const Eigen::Vector2d e1(1, 0), e2(0, 1), s0(S, 0);
  const Eigen::RowVectorXd &Phi_bar = mi.Phi_bar, &Phi_tilde = mi.Phi_tilde;

  // Body-frame generalized force and its (θ, q) derivative of each actuator at q = 0,
  // packed as [Gb; vec(DGb)], each of the form A + B cos θ + C sin θ.
  const int len = N + N * (1 + n);
  auto packed = [&](int e, double theta) {
    const FlexibleBody::ForceDerivative fd = body.element_force_derivative(e, theta, q0);
    const Eigen::Matrix2d Ct = rot(theta).transpose();
    Eigen::VectorXd G = fd.value;
    Eigen::MatrixXd DG = fd.derivative;
    G.head<2>() = Ct * fd.value.head<2>();
    DG.topRows<2>() = Ct * fd.derivative.topRows<2>();
    DG.block<2, 1>(0, 0) -= J * G.head<2>();  // ∂Cᵀ/∂θ = −J Cᵀ
    Eigen::VectorXd v(len);
    v.head(N) = G;
    v.tail(N * (1 + n)) = Eigen::Map<const Eigen::VectorXd>(DG.data(), N * (1 + n));
    return v;
  };
  const double half_pi = 0.5 * std::acos(-1.0), pi = std::acos(-1.0);
  std::vector<Eigen::VectorXd> trig[3];  // A, B, C per actuator
  for (int k = 0; k < nu_; ++k) {
    const int e = actuators_[k];
    const Eigen::VectorXd v0 = packed(e, 0.0), v1 = packed(e, half_pi), v2 = packed(e, pi);
    Eigen::VectorXd A = 0.5 * (v0 + v2), B = 0.5 * (v0 - v2), C = v1 - A;
    const double scale = 1.0 + v0.cwiseAbs().maxCoeff() + v1.cwiseAbs().maxCoeff();
    // Body-fixed elements have no cos/sin part: drop the round-off of the samples.
    if (B.cwiseAbs().maxCoeff() <= 1e-13 * scale) B.setZero();
    if (C.cwiseAbs().maxCoeff() <= 1e-13 * scale) C.setZero();
    const double th = 1.234;
    if ((packed(e, th) - (A + B * std::cos(th) + C * std::sin(th))).cwiseAbs().maxCoeff() > 1e-11 * scale)
      throw std::logic_error("elastic dynamics: element '" + body.elements()[e].name +
                             "' is not of the form A + B cos(theta) + C sin(theta) in body axes at q = 0");
    trig[0].push_back(A);
    trig[1].push_back(B);
    trig[2].push_back(C);
  }
  for (int b = 0; b < 3; ++b) {
    G_trig_[b].resize(N, nu_);
    for (int k = 0; k < nu_; ++k) G_trig_[b].col(k) = trig[b][k].head(N);
  }

  const Eigen::MatrixXd& Dmp = body.damping();
  // One feature's K_pos (N x (1+n)), K_vel (N x N) and r (N), eq. 11.4.
  auto add_feature = [&](Kind kind, int actuator, const Eigen::VectorXd* packed_coef, std::vector<Eigen::MatrixXd>& Ps,
                         std::vector<Eigen::VectorXd>& cs) {
    Eigen::VectorXd G = Eigen::VectorXd::Zero(N);
    Eigen::MatrixXd DG = Eigen::MatrixXd::Zero(N, 1 + n);
    if (packed_coef) {
      G = packed_coef->head(N);
      DG = Eigen::Map<const Eigen::MatrixXd>(packed_coef->data() + N, N, 1 + n);
    }
    // Zero-order accelerations of this feature (eq. 6.3 in body axes).
    const double alpha = (G(2) - S * G(1) / m) / D;
    Eigen::Vector2d a = (G.head<2>() - alpha * S * e2) / m;
    if (kind == Kind::Omega2) a += S * e1 / m;
    const double ax = a(0);
    Eigen::MatrixXd Kpos = DG, Kvel = Eigen::MatrixXd::Zero(N, N);
    Eigen::VectorXd r = Eigen::VectorXd::Zero(N);
    Kpos.block<2, 1>(0, 0) += m * J * a;
    Kpos.block(0, 1, 2, n) += -alpha * J * e2 * Phi_bar;
    Kpos(2, 0) += s0.dot(a);
    Kpos.block(2, 1, 1, n) += ax * Phi_bar;
    Kpos.block(3, 0, n, 1) += ax * Phi_bar.transpose();
    Kpos.block(3, 1, n, n) += ax * stiff.H_bar;
    // Per-element axial-load stiffening (the other half of geometric stiffening): for an
    // actuator feature, + sgn(x_a) (e1ᵀ of its body-frame unit force) H(x_a) in the q rows,
    // once FlexibleBody provides H(x_a).
    if (kind == Kind::One) {
      Kpos.block(3, 1, n, n) -= mi.K;
      Kvel -= Dmp;  // modal damping (eq. 6.5): no rigid rows or columns, frame-invariant
    }
    if (kind == Kind::Omega2) {
      Kpos.block(0, 1, 2, n) += e2 * Phi_bar;
      Kpos.block(3, 1, n, n) += mi.M - stiff.G_c;
    }
    if (kind == Kind::Omega) {
      Kvel.block<2, 2>(0, 0) -= m * J;
      Kvel.block<2, 1>(0, 2) += 2.0 * s0;
      Kvel.block(0, 3, 2, n) += 2.0 * e1 * Phi_bar;
      Kvel.block<1, 2>(2, 0) -= s0.transpose();
      Kvel.block(3, 0, n, 2) -= Phi_bar.transpose() * e1.transpose();
    }
    // Residual of the full model on the zero-order motion: q rows only (eq. 7.2).
    r.tail(n) = G.tail(n) - Phi_bar.transpose() * a(1) - Phi_tilde.transpose() * alpha;
    Eigen::MatrixXd KK(nr, nx1);
    KK << TN.transpose() * Kpos * Tpos, TN.transpose() * Kvel * TN;
    Eigen::MatrixXd P = Mb_ldlt.solve(KK);
    Eigen::VectorXd c = Mb_ldlt.solve(TN.transpose() * r);
    if (P.isZero(0.0) && c.isZero(0.0)) return;
    features_.push_back({kind, actuator});
    Ps.push_back(std::move(P));
    cs.push_back(std::move(c));
  };
  std::vector<Eigen::MatrixXd> Ps;
  std::vector<Eigen::VectorXd> cs;
  add_feature(Kind::One, -1, nullptr, Ps, cs);
  add_feature(Kind::Omega, -1, nullptr, Ps, cs);
  add_feature(Kind::Omega2, -1, nullptr, Ps, cs);
  for (int k = 0; k < nu_; ++k) {
    add_feature(Kind::U, k, &trig[0][k], Ps, cs);
    if (!trig[1][k].isZero(0.0)) add_feature(Kind::UCos, k, &trig[1][k], Ps, cs);
    if (!trig[2][k].isZero(0.0)) add_feature(Kind::USin, k, &trig[2][k], Ps, cs);
  }
  const int F = static_cast<int>(features_.size());
  P_.resize(static_cast<Eigen::Index>(F) * nr, nx1);
  c_.resize(static_cast<Eigen::Index>(F) * nr);
  for (int i = 0; i < F; ++i) {
    P_.middleRows(static_cast<Eigen::Index>(i) * nr, nr) = Ps[i];
    c_.segment(static_cast<Eigen::Index>(i) * nr, nr) = cs[i];
  }

  // Structure over p = (θ0, θ0', u): which entries can be nonzero.
  std::vector<bool> act(np(), false);
  std::vector<std::pair<int, int>> pp;
  for (const Feature& f : features_) {
    switch (f.kind) {
      case Kind::One: break;
      case Kind::Omega: act[1] = true; break;
      case Kind::Omega2:
        act[1] = true;
        pp.emplace_back(1, 1);
        break;
      case Kind::U: act[2 + f.actuator] = true; break;
      case Kind::UCos:
      case Kind::USin:
        theta_used_ = true;
        act[0] = act[2 + f.actuator] = true;
        pp.emplace_back(0, 0);
        pp.emplace_back(2 + f.actuator, 0);
        break;
    }
  }
  std::sort(pp.begin(), pp.end());
  pp.erase(std::unique(pp.begin(), pp.end()), pp.end());
  pp_pattern_ = pp;
  for (int i = 0; i < np(); ++i)
    if (act[i]) active_p_.push_back(i);

  omega_ = omega_all.head(m_);
  modal_rows_ = truncated_ ? Eigen::MatrixXd(Eigen::MatrixXd::Identity(m_, m_)) : rows_all;
  const Eigen::MatrixXd M_c =
      mi.M - Mb_.block(3, 0, n, 3) * Mb_.topLeftCorner<3, 3>().ldlt().solve(Mb_.block(0, 3, 3, n));
  K_ = B_.transpose() * mi.K * B_;
  M_c_ = B_.transpose() * M_c * B_;
  const Beam& beam = body.beam();
  phi_left_ = body.basis().evaluate(beam.x_of(0.0)).phi * B_;
  phi_right_ = body.basis().evaluate(beam.x_of(beam.length())).phi * B_;
}

std::vector<int> ElasticDynamics::excited_modes(double theta) const {
  std::vector<bool> ex(n_, false);
  const Eigen::MatrixXd G = G_trig_[0] + G_trig_[1] * std::cos(theta) + G_trig_[2] * std::sin(theta);
  // The body-frame force's participation equals the inertial one at θ (𝕄 rotates alike).
  const Eigen::MatrixXd part = V_.transpose() * G;  // n x nu
  for (int k = 0; k < nu_; ++k) {
    const double pmax = part.col(k).cwiseAbs().maxCoeff();
    for (int j = 0; j < n_; ++j)
      if (pmax > 0.0 && std::abs(part(j, k)) > 1e-8 * pmax) ex[j] = true;
  }
  std::vector<int> out;  // of the modes x1 holds
  for (int j = 0; j < m_; ++j)
    if (ex[j]) out.push_back(j);
  return out;
}

ElasticDynamics::Data ElasticDynamics::create_data() const {
  Data d;
  d.f.setZero(nx());
  d.Jx.setZero(nx(), nx());
  d.Jp.setZero(nx(), np());
  d.Hpp.setZero(np(), np());
  d.Hpx.setZero(np(), nx());
  d.Y.setZero(P_.rows());
  d.phi.setZero(static_cast<Eigen::Index>(features_.size()));
  return d;
}

double ElasticDynamics::value(const Feature& f, double c, double s, double omega,
                              const Eigen::Ref<const Eigen::VectorXd>& u) const {
  switch (f.kind) {
    case Kind::One: return 1.0;
    case Kind::Omega: return omega;
    case Kind::Omega2: return omega * omega;
    case Kind::U: return u(f.actuator);
    case Kind::UCos: return u(f.actuator) * c;
    case Kind::USin: return u(f.actuator) * s;
  }
  return 0.0;
}

int ElasticDynamics::first(const Feature& f, double c, double s, double omega,
                           const Eigen::Ref<const Eigen::VectorXd>& u, int* idx, double* d) const {
  const int iu = 2 + f.actuator;
  switch (f.kind) {
    case Kind::One: return 0;
    case Kind::Omega: idx[0] = 1, d[0] = 1.0; return 1;
    case Kind::Omega2: idx[0] = 1, d[0] = 2.0 * omega; return 1;
    case Kind::U: idx[0] = iu, d[0] = 1.0; return 1;
    case Kind::UCos:
      idx[0] = 0, d[0] = -u(f.actuator) * s;
      idx[1] = iu, d[1] = c;
      return 2;
    case Kind::USin:
      idx[0] = 0, d[0] = u(f.actuator) * c;
      idx[1] = iu, d[1] = s;
      return 2;
  }
  return 0;
}

int ElasticDynamics::second(const Feature& f, double c, double s, const Eigen::Ref<const Eigen::VectorXd>& u, int* ia,
                            int* ib, double* d) const {
  const int iu = 2 + f.actuator;
  switch (f.kind) {
    case Kind::Omega2: ia[0] = ib[0] = 1, d[0] = 2.0; return 1;
    case Kind::UCos:
      ia[0] = ib[0] = 0, d[0] = -u(f.actuator) * c;
      ia[1] = iu, ib[1] = 0, d[1] = -s;
      return 2;
    case Kind::USin:
      ia[0] = ib[0] = 0, d[0] = -u(f.actuator) * s;
      ia[1] = iu, ib[1] = 0, d[1] = c;
      return 2;
    default: return 0;
  }
}

void ElasticDynamics::calc(Data& data, double theta, double omega, const Eigen::Ref<const Eigen::VectorXd>& u,
                           const Eigen::Ref<const Eigen::VectorXd>& x1) const {
  const double c = theta_used_ ? std::cos(theta) : 1.0, s = theta_used_ ? std::sin(theta) : 0.0;
  data.Y.noalias() = P_ * x1;
  data.Y += c_;
  data.f.head(m_ + 1) = x1.tail(m_ + 1);
  auto acc = data.f.tail(na_);
  acc.setZero();
  for (std::size_t i = 0; i < features_.size(); ++i) {
    const double v = value(features_[i], c, s, omega, u);
    data.phi(static_cast<Eigen::Index>(i)) = v;
    if (v != 0.0) acc += v * data.Y.segment(static_cast<Eigen::Index>(i) * na_, na_);
  }
}

void ElasticDynamics::calc_diff(Data& data, double theta, double omega, const Eigen::Ref<const Eigen::VectorXd>& u,
                                const Eigen::Ref<const Eigen::VectorXd>& x1) const {
  calc(data, theta, omega, u, x1);
  const double c = theta_used_ ? std::cos(theta) : 1.0, s = theta_used_ ? std::sin(theta) : 0.0;
  data.Jx.setZero();
  data.Jp.setZero();
  for (int i = 0; i <= m_; ++i) data.Jx(i, m_ + 3 + i) = 1.0;
  auto Jacc = data.Jx.bottomRows(na_);
  int idx[2];
  double d[2];
  for (std::size_t i = 0; i < features_.size(); ++i) {
    const Eigen::Index off = static_cast<Eigen::Index>(i) * na_;
    const double v = data.phi(static_cast<Eigen::Index>(i));
    if (v != 0.0) Jacc += v * P_.middleRows(off, na_);
    const int k = first(features_[i], c, s, omega, u, idx, d);
    for (int j = 0; j < k; ++j) data.Jp.col(idx[j]).tail(na_) += d[j] * data.Y.segment(off, na_);
  }
}

void ElasticDynamics::calc_hessian(Data& data, double theta, double omega, const Eigen::Ref<const Eigen::VectorXd>& u,
                                   const Eigen::Ref<const Eigen::VectorXd>& x1,
                                   const Eigen::Ref<const Eigen::VectorXd>& lambda) const {
  const double c = theta_used_ ? std::cos(theta) : 1.0, s = theta_used_ ? std::sin(theta) : 0.0;
  data.Y.noalias() = P_ * x1;
  data.Y += c_;
  data.Hpp.setZero();
  data.Hpx.setZero();
  const auto lam = lambda.tail(na_);  // the position rows are linear in x1
  int idx[2], ia[2], ib[2];
  double d[2], d2[2];
  for (std::size_t i = 0; i < features_.size(); ++i) {
    const Eigen::Index off = static_cast<Eigen::Index>(i) * na_;
    const int k1 = first(features_[i], c, s, omega, u, idx, d);
    if (k1 == 0) continue;
    const Eigen::RowVectorXd l = lam.transpose() * P_.middleRows(off, na_);
    for (int j = 0; j < k1; ++j) data.Hpx.row(idx[j]) += d[j] * l;
    const int k2 = second(features_[i], c, s, u, ia, ib, d2);
    if (k2 == 0) continue;
    const double si = lam.dot(data.Y.segment(off, na_));
    for (int j = 0; j < k2; ++j) {
      data.Hpp(ia[j], ib[j]) += d2[j] * si;
      if (ia[j] != ib[j]) data.Hpp(ib[j], ia[j]) += d2[j] * si;
    }
  }
}

}  // namespace freeflex
