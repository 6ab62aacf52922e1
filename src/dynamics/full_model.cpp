#include "freeflex/dynamics/full_model.hpp"

#include <cmath>

#include "planar.hpp"

namespace freeflex {
namespace {
using planar::rot;
const Eigen::Matrix2d& kJ = planar::J();
}  // namespace

FullModel::FullModel(const FlexibleBody& body) : body_(body) {
  const int N = body_.dofs();
  Eigen::MatrixXd Mb0(N, N);
  body_.mass_matrix(0.0, Eigen::VectorXd::Zero(body_.n()), Mb0);
  rest_llt_.compute(Mb0);
  W_.setZero(N, 2);
  W_(0, 0) = W_(2, 1) = 1.0;
  rest_llt_.solveInPlace(W_);
}

FullModel::Data FullModel::create_data() const {
  const int N = body_.dofs();
  Data d;
  d.G.resize(N);
  d.b.resize(N);
  d.Mq.resize(body_.n());
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
  Eigen::MatrixXd Mz(N, N);
  body_.mass_matrix(z(2), z.tail(n), Mz);
  Eigen::VectorXd h(N), G(N), Mq(n);
  bias(z, zd, h, Mq);
  body_.generalized_force(z(2), z.tail(n), commands, G);
  return Mz * zdd + h - G;
}

bool FullModel::rhs(Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                    const Eigen::Ref<const Eigen::VectorXd>& commands, Eigen::Ref<Eigen::VectorXd> x_dot) const {
  const int N = body_.dofs(), n = body_.n();
  const auto z = x.head(N);
  const auto zd = x.tail(N);
  const auto q = z.tail(n);
  bias(z, zd, d.b, d.Mq);
  body_.generalized_force(z(2), q, commands, d.G);
  Eigen::VectorXd& f = d.G;
  f -= d.b;
  // 𝕄 z'' = f  ⇔  𝕄_b (Tᵀ z'') = Tᵀ f, with 𝕄_b = 𝕄_b(0) + U S Uᵀ, U = [e_x, e_θ]:
  // w = y − W S (I + Uᵀ W S)⁻¹ Uᵀ y with y = 𝕄_b(0)⁻¹ Tᵀ f (no S⁻¹: S is singular at q = 0).
  const Eigen::Matrix2d C = rot(z(2));
  f.head<2>() = C.transpose() * f.head<2>();
  rest_llt_.solveInPlace(f);
  const double a = -body_.integrals().Phi_bar.dot(q), c = q.dot(d.Mq);
  Eigen::Matrix2d S;
  S << 0.0, a, a, c;
  Eigen::Matrix2d UtW;
  UtW << W_(0, 0), W_(0, 1), W_(2, 0), W_(2, 1);
  const Eigen::Matrix2d cap = Eigen::Matrix2d::Identity() + UtW * S;
  // det 𝕄_b = det 𝕄_b(0) · det(cap): a non-positive determinant means 𝕄 is not positive definite
  const double det = cap.determinant();
  if (!(det > 0.0)) return false;
  const Eigen::Vector2d v = cap.inverse() * Eigen::Vector2d(f(0), f(2));
  f.noalias() -= W_ * (S * v);
  f.head<2>() = C * f.head<2>();
  x_dot.head(N) = zd;
  x_dot.tail(N) = f;
  return true;
}

double FullModel::energy(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const int N = body_.dofs(), n = body_.n();
  Eigen::MatrixXd Mz(N, N);
  body_.mass_matrix(x(2), x.segment(3, n), Mz);
  const auto zd = x.tail(N);
  const auto q = x.segment(3, n);
  return 0.5 * zd.dot(Mz * zd) + 0.5 * q.dot(body_.integrals().K * q);
}

Eigen::Vector2d FullModel::linear_momentum(const Eigen::Ref<const Eigen::VectorXd>& x) const {
  const ModalIntegrals& mi = body_.integrals();
  const int N = body_.dofs(), n = body_.n();
  const Eigen::Matrix2d C = rot(x(2));
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
  return mi.m * cross(R, Rd) + thd * R.dot(C * s) + cross(R, C.col(1)) * Pqd + cross(C * s, Rd) +
         thd * (mi.I_o + q.dot(mi.M * q)) + mi.Phi_tilde.dot(zd.tail(n));
}

}  // namespace freeflex
