// The discretized flexible body: mass matrix, generalized forces of the force elements
// and their derivatives, modal damping, vibration energy.
#include "freeflex/dynamics/flexible_body.hpp"

#include <cassert>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "dynamics/body_kernels.hpp"
#include "planar.hpp"
#include "util/format.hpp"

namespace freeflex {
namespace {

using planar::rot;
const Eigen::Matrix2d& kJ = planar::J();

/// Inertial force per unit command (eq. 6.4a, 6.4b) and its derivative with respect to
/// the angle psi = θ (+ Φ'(x_a) q when following the slope) that turns it; a force with
/// inertial components does not turn (derivative zero).
/// `C_psi`: rot(psi) when the caller has it already (one sine and cosine fewer).
void applied_force(const ForceElement& el, double psi, Eigen::Vector2d& f, Eigen::Vector2d& df_dpsi,
                   const Eigen::Matrix2d* C_psi = nullptr) {
  if (el.type == ForceElement::Type::Force) {
    f = el.direction;
    df_dpsi.setZero();
    return;
  }
  const Eigen::Matrix2d Cp = C_psi ? *C_psi : rot(psi);
  f = Cp * el.direction;
  df_dpsi = Cp * kJ * el.direction;
}

}  // namespace

FlexibleBody::FlexibleBody(const Beam& beam, int noa, std::vector<ForceElement> elements,
                           std::vector<double> damping_ratios, bool geometric_stiffening)
    : FlexibleBody(beam, noa, BasisOptions{}, std::move(elements), std::move(damping_ratios), geometric_stiffening) {}

FlexibleBody::FlexibleBody(const Beam& beam, int modes, const BasisOptions& basis,
                           std::vector<ForceElement> elements, std::vector<double> damping_ratios,
                           bool geometric_stiffening)
    : FlexibleBody(beam, make_basis(beam, modes, basis), std::move(elements), std::move(damping_ratios),
                   geometric_stiffening) {}

FlexibleBody::FlexibleBody(const Beam& beam, std::shared_ptr<const ShapeBasis> basis,
                           std::vector<ForceElement> elements, std::vector<double> damping_ratios,
                           bool geometric_stiffening)
    : beam_(beam),
      basis_(basis ? std::move(basis) : throw std::invalid_argument("FlexibleBody: no shape basis")),
      mi_(geometric_stiffening ? stiffened_modal_integrals(beam_, *basis_) : modal_integrals(beam_, *basis_)),
      elements_(std::move(elements)),
      stiffening_(geometric_stiffening) {
  for (const auto& e : elements_) {
    if (!std::isfinite(e.position_m) || e.position_m < 0.0 || e.position_m > beam_.length()) {
      std::ostringstream os;
      os << "force element '" << e.name << "': position_m = " << e.position_m << ", must lie on the beam [0, "
         << beam_.length() << "]";
      throw std::invalid_argument(os.str());
    }
    const double x = beam_.x_of(e.position_m);
    const BasisValues v = basis_->evaluate(x);
    x_.push_back(x);
    phi_.push_back(v.phi);
    dphi_.push_back(v.dphi);
    H_.push_back(stiffening_ ? foreshortening_matrix(beam_, *basis_, x) : Eigen::MatrixXd());
  }
  const int n = basis_->size(), N = 3 + n;
  // Schur complement of the rigid block of the rest mass matrix (eq. 6.8).
  const Eigen::MatrixXd M0 = mass_matrix(0.0, Eigen::VectorXd::Zero(n));
  M_condensed_ = mi_.M - M0.block(3, 0, n, 3) * M0.topLeftCorner<3, 3>().ldlt().solve(M0.block(0, 3, 3, n));
  D_.setZero(N, N);
  for (double z : damping_ratios)
    if (!(z >= 0.0) || !std::isfinite(z)) throw std::invalid_argument("damping ratio must be finite and >= 0");
  if (!damping_ratios.empty()) {
    // D = 𝕄0 V diag(2 zeta omega) Vᵀ 𝕄0 over the mass-normalized elastic modes at rest:
    // it damps mode i at ratio zeta_i and exerts no force on rigid motion.
    Eigen::MatrixXd K0 = Eigen::MatrixXd::Zero(N, N);
    K0.bottomRightCorner(n, n) = mi_.K;
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(K0, M0);
    for (int i = 0; i < static_cast<int>(damping_ratios.size()) && i < n; ++i) {
      const double omega = std::sqrt(std::max(0.0, es.eigenvalues()(3 + i)));
      const Eigen::VectorXd Mv = M0 * es.eigenvectors().col(3 + i);
      D_.noalias() += (2.0 * damping_ratios[i] * omega) * Mv * Mv.transpose();
      damped_ = damped_ || damping_ratios[i] > 0.0;
    }
  }
}

int FlexibleBody::element_index(const std::string& name) const {
  for (std::size_t i = 0; i < elements_.size(); ++i)
    if (elements_[i].name == name) return static_cast<int>(i);
  return -1;
}

Eigen::MatrixXd FlexibleBody::mass_matrix(double theta, const Eigen::Ref<const Eigen::VectorXd>& q) const {
  Eigen::MatrixXd out;
  mass_matrix_into(theta, q, out);
  return out;
}

void FlexibleBody::mass_matrix_into(double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                                    Eigen::MatrixXd& out) const {
  const int n = this->n();
  const Eigen::Matrix2d C = rot(theta);
  if (stiffening_) {
    // eq. 14.5: s(q) = [S_o − ½ qᵀH̄q, Φ̄q], B(q) = [−(H̄q)ᵀ; Φ̄], I(q) = I_o + qᵀ(M − G_c)q
    const Eigen::VectorXd Hq = mi_.H_bar * q;
    const Eigen::Vector2d s(mi_.S_o - 0.5 * q.dot(Hq), mi_.Phi_bar.dot(q));
    Eigen::MatrixXd B(2, n);
    B.row(0) = -Hq.transpose();
    B.row(1) = mi_.Phi_bar;
    out.setZero(dofs(), dofs());
    out(0, 0) = out(1, 1) = mi_.m;
    out.block<2, 1>(0, 2) = C * kJ * s;
    out.block<1, 2>(2, 0) = (C * kJ * s).transpose();
    out.block(0, 3, 2, n) = C * B;
    out.block(3, 0, n, 2) = (C * B).transpose();
    out(2, 2) = mi_.I_o + q.dot((mi_.M - mi_.G_c) * q);
    out.block(2, 3, 1, n) = mi_.Phi_tilde;
    out.block(3, 2, n, 1) = mi_.Phi_tilde.transpose();
    out.bottomRightCorner(n, n) = mi_.M;
    return;
  }
  const Eigen::Vector2d s(mi_.S_o, mi_.Phi_bar.dot(q));  // s(q) = ∫p dm, eq. 3.3
  out.setZero(dofs(), dofs());
  out(0, 0) = out(1, 1) = mi_.m;
  const Eigen::Vector2d MRth = C * kJ * s;                 // C J s
  const Eigen::Vector2d Ce2 = C.col(1);                    // C e2
  out.block<2, 1>(0, 2) = MRth;
  out.block<1, 2>(2, 0) = MRth.transpose();
  out.block(0, 3, 2, n).noalias() = Ce2 * mi_.Phi_bar;
  out.block(3, 0, n, 2) = out.block(0, 3, 2, n).transpose();
  double qMq = 0.0;  // qᵀ M q without a temporary: this runs in every right-hand side
  for (int i = 0; i < n; ++i) qMq += q(i) * mi_.M.col(i).dot(q);
  out(2, 2) = mi_.I_o + qMq;
  out.block(2, 3, 1, n) = mi_.Phi_tilde;
  out.block(3, 2, n, 1) = mi_.Phi_tilde.transpose();
  out.bottomRightCorner(n, n) = mi_.M;
}

namespace {

/// Generalized force of element e per unit command at (theta, q) into g and, if d is
/// given, its derivative with respect to (theta, q) into d (eq. 6.4).
void element_force_kernel(const FlexibleBody& body, int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                        Eigen::Ref<Eigen::VectorXd> g, Eigen::MatrixXd* d) {
  const int n = body.n();
  const ForceElement& el = body.elements()[e];
  const Eigen::RowVectorXd& phi = body.element_phi(e);
  const Eigen::RowVectorXd& dphi = body.element_slope(e);
  g.setZero();
  if (d) d->setZero(3 + n, 1 + n);
  if (el.type == ForceElement::Type::Torque) {
    // virtual rotation at x_a is δθ + Φ'(x_a) δq (eq. 6.4c)
    g(2) = 1.0;
    g.tail(n) = dphi.transpose();
    return;
  }
  // Inertial force f(theta, q) and its derivatives (eq. 6.4a, 6.4b).
  const bool follows = el.type == ForceElement::Type::Thruster && el.follow_slope;
  Eigen::Vector2d f, df_dth;
  // a thruster that does not follow the slope points at θ: its rotation is C (at θ = −0.0
  // the sign of a zero force component may differ from rot(θ + 0.0); nothing else)
  const Eigen::Matrix2d C = rot(theta);
  applied_force(el, theta + (follows ? dphi.dot(q) : 0.0), f, df_dth, follows ? nullptr : &C);
  // Body components w = Cᵀ f; then M_o = wᵀ J p = -w_x u_a + w_y x_a, Q = Φ_aᵀ w_y.
  const double xa = body.element_x(e), ua = phi.dot(q);
  const Eigen::Vector2d w = C.transpose() * f;
  g.head<2>() = f;
  g(2) = -w(0) * ua + w(1) * xa;
  g.tail(n) = phi.transpose() * w(1);
  // eq. 14.7: the point has moved towards o by h_a = ½ qᵀH_a q, and δp_x = −sgn(x_a)(H_a q)ᵀδq
  Eigen::VectorXd Haq;
  double sa = 0.0, ha = 0.0;
  if (body.geometric_stiffening() && xa != 0.0) {
    sa = xa > 0.0 ? 1.0 : -1.0;
    Haq = body.element_foreshortening(e) * q;
    ha = 0.5 * q.dot(Haq);
    g(2) -= w(1) * sa * ha;
    g.tail(n) -= (sa * w(0)) * Haq;
  }
  if (!d) return;
  const Eigen::MatrixXd df_dq = follows ? Eigen::MatrixXd(df_dth * dphi) : Eigen::MatrixXd::Zero(2, n);
  const Eigen::Vector2d dw_dth = kJ.transpose() * w + C.transpose() * df_dth;
  const Eigen::MatrixXd dw_dq = C.transpose() * df_dq;
  d->block<2, 1>(0, 0) = df_dth;
  d->block(0, 1, 2, n) = df_dq;
  (*d)(2, 0) = -dw_dth(0) * ua + dw_dth(1) * xa;
  d->block(2, 1, 1, n) = -ua * dw_dq.row(0) - w(0) * phi + xa * dw_dq.row(1);
  d->block(3, 0, n, 1) = phi.transpose() * dw_dth(1);
  d->block(3, 1, n, n) = phi.transpose() * dw_dq.row(1);
  if (sa != 0.0) {
    const Eigen::MatrixXd& Ha = body.element_foreshortening(e);
    (*d)(2, 0) -= dw_dth(1) * sa * ha;
    d->block(2, 1, 1, n) -= sa * (ha * dw_dq.row(1) + w(1) * Haq.transpose());
    d->block(3, 0, n, 1) -= (sa * dw_dth(0)) * Haq;
    d->block(3, 1, n, n) -= sa * (Haq * dw_dq.row(0) + w(0) * Ha);
  }
}

}  // namespace

Eigen::VectorXd FlexibleBody::element_force(int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q) const {
  Eigen::VectorXd g(dofs());
  element_force_into(e, theta, q, g);
  return g;
}

void FlexibleBody::element_force_into(int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                                      Eigen::Ref<Eigen::VectorXd> out) const {
  element_force_kernel(*this, e, theta, q, out, nullptr);
}

FlexibleBody::ForceDerivative FlexibleBody::element_force_derivative(int e, double theta,
                                                                     const Eigen::Ref<const Eigen::VectorXd>& q) const {
  ForceDerivative r;
  r.value.resize(dofs());
  element_force_kernel(*this, e, theta, q, r.value, &r.derivative);
  return r;
}

Eigen::VectorXd FlexibleBody::generalized_force(double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                                                const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  Eigen::VectorXd G(dofs());
  detail::generalized_force(*this, theta, q, commands, G);
  return G;
}

FlexibleBody::ForceDerivative FlexibleBody::generalized_force_derivative(
    double theta, const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& commands) const {
  const int N = dofs();
  ForceDerivative r;
  r.value = Eigen::VectorXd::Zero(N);
  r.derivative.setZero(N, 1 + n());
  Eigen::VectorXd g(N);
  Eigen::MatrixXd dg;
  for (int e = 0; e < static_cast<int>(elements_.size()); ++e) {
    if (commands(e) == 0.0) continue;
    element_force_kernel(*this, e, theta, q, g, &dg);
    r.value += commands(e) * g;
    r.derivative += commands(e) * dg;
  }
  return r;
}

namespace {

/// The generalized forces of detail:: with element e's rows given (phi, dphi: Φ(x_e),
/// Φ'(x_e) in the coordinates q is given in; Ha: H(x_e) in them, read with geometric
/// stiffening only).
void add_force_with_rows(const FlexibleBody& body, int e, const Eigen::RowVectorXd& phi, const Eigen::RowVectorXd& dphi,
                         const Eigen::MatrixXd& Ha, double theta, const Eigen::Ref<const Eigen::VectorXd>& q, double scale,
                         Eigen::Ref<Eigen::VectorXd> G, double d_theta, const Eigen::VectorXd* d_q, Eigen::VectorXd* dG) {
  const int n = static_cast<int>(phi.size());
  const ForceElement& el = body.elements()[e];
  if (el.type == ForceElement::Type::Torque) {  // eq. 6.4c: no dependence on configuration
    double* g = G.data();
    const double* slope = dphi.data();
    g[2] += scale;
    for (int i = 0; i < n; ++i) g[3 + i] += scale * slope[i];
    return;
  }
  // Same steps as element_force, along one direction (d_theta, d_q) instead of a Jacobian.
  const bool follows = el.type == ForceElement::Type::Thruster && el.follow_slope;
  Eigen::Vector2d f, df;
  const Eigen::Matrix2d C = rot(theta);  // a thruster that does not follow the slope points at θ
  applied_force(el, theta + (follows ? dphi.dot(q) : 0.0), f, df, follows ? nullptr : &C);
  df *= d_theta + (follows && d_q ? dphi.dot(*d_q) : 0.0);
  const double xa = body.element_x(e), ua = phi.dot(q);
  const Eigen::Vector2d w = C.transpose() * f;
  G.head<2>() += scale * f;
  G(2) += scale * (-w(0) * ua + w(1) * xa);
  G.tail(n).noalias() += (scale * w(1)) * phi.transpose();
  const bool shortens = body.geometric_stiffening() && xa != 0.0;  // eq. 14.7
  const double sa = xa > 0.0 ? 1.0 : -1.0;
  if (shortens) {
    const double ha = 0.5 * q.dot(Ha * q);
    G(2) -= scale * w(1) * sa * ha;
    G.tail(n).noalias() -= (scale * sa * w(0)) * (Ha * q);
  }
  if (!dG) return;
  const Eigen::Vector2d dw = d_theta * (kJ.transpose() * w) + C.transpose() * df;
  const double dua = d_q ? phi.dot(*d_q) : 0.0;
  dG->head<2>() += scale * df;
  (*dG)(2) += scale * (-dw(0) * ua - w(0) * dua + dw(1) * xa);
  dG->tail(n).noalias() += (scale * dw(1)) * phi.transpose();
  if (shortens) {
    const Eigen::VectorXd Haq = Ha * q;
    const double ha = 0.5 * q.dot(Haq), dha = d_q ? Haq.dot(*d_q) : 0.0;
    (*dG)(2) -= scale * sa * (dw(1) * ha + w(1) * dha);
    dG->tail(n).noalias() -= (scale * sa * dw(0)) * Haq;
    if (d_q) dG->tail(n).noalias() -= (scale * sa * w(0)) * (Ha * *d_q);
  }
}

/// G = Σ_e commands(e) add(e, commands(e)), elements with a zero command skipped. Plain
/// loops: this runs at every right-hand side of the full model, where Eigen's dynamic-size
/// set-up cost more than the sums (docs/benchmarks.md).
template <class Add>
void sum_element_forces(const FlexibleBody& body, const Eigen::Ref<const Eigen::VectorXd>& commands,
                        Eigen::Ref<Eigen::VectorXd> G, const Add& add) {
  double* g = G.data();
  for (Eigen::Index i = 0; i < G.size(); ++i) g[i] = 0.0;
  const int ne = static_cast<int>(body.elements().size());
  assert(commands.size() >= ne);
  const double* u = commands.data();
  for (int e = 0; e < ne; ++e)
    if (u[e] != 0.0) add(e, u[e]);
}

}  // namespace

void detail::generalized_force(const FlexibleBody& body, double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                               const Eigen::Ref<const Eigen::VectorXd>& commands, Eigen::Ref<Eigen::VectorXd> G) {
  sum_element_forces(body, commands, G, [&](int e, double u) { add_element_force(body, e, theta, q, u, G); });
}

void detail::add_element_force(const FlexibleBody& body, int e, double theta, const Eigen::Ref<const Eigen::VectorXd>& q,
                               double scale, Eigen::Ref<Eigen::VectorXd> G, double d_theta, const Eigen::VectorXd* d_q,
                               Eigen::VectorXd* dG) {
  add_force_with_rows(body, e, body.element_phi(e), body.element_slope(e), body.element_foreshortening(e), theta, q,
                      scale, G, d_theta, d_q, dG);
}

detail::ElementRows::ElementRows(const FlexibleBody& body, const Eigen::MatrixXd& Psi) {
  for (int e = 0; e < static_cast<int>(body.elements().size()); ++e) {
    phi.push_back(body.element_phi(e) * Psi);
    slope.push_back(body.element_slope(e) * Psi);
    const Eigen::MatrixXd& Ha = body.element_foreshortening(e);
    H.push_back(Ha.size() ? Eigen::MatrixXd(Psi.transpose() * Ha * Psi) : Eigen::MatrixXd());
  }
}

void detail::add_element_force(const FlexibleBody& body, const ElementRows& rows, int e, double theta,
                               const Eigen::Ref<const Eigen::VectorXd>& q, double scale, Eigen::Ref<Eigen::VectorXd> G) {
  add_force_with_rows(body, e, rows.phi[e], rows.slope[e], rows.H[e], theta, q, scale, G, 0.0, nullptr, nullptr);
}

void detail::generalized_force(const FlexibleBody& body, const ElementRows& rows, double theta,
                               const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& commands,
                               Eigen::Ref<Eigen::VectorXd> G) {
  sum_element_forces(body, commands, G, [&](int e, double u) { add_element_force(body, rows, e, theta, q, u, G); });
}

double FlexibleBody::vibration_energy(const Eigen::Ref<const Eigen::VectorXd>& q,
                                      const Eigen::Ref<const Eigen::VectorXd>& q_dot) const {
  return 0.5 * q_dot.dot(M_condensed_ * q_dot) + 0.5 * q.dot(mi_.K * q);
}

RestModes rest_modes(const FlexibleBody& body) {
  const int n = body.n();
  const Eigen::MatrixXd M0 = body.mass_matrix(0.0, Eigen::VectorXd::Zero(n));
  const Eigen::Matrix3d Mrr = M0.topLeftCorner<3, 3>();
  const Eigen::MatrixXd Mrq = M0.topRightCorner(3, n);
  RestModes r;
  r.T = Mrr.ldlt().solve(Mrq);
  r.M_c = body.condensed_mass();  // M_qq − M_qr T, formed once by the body
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(body.integrals().K, r.M_c);
  if (es.info() != Eigen::Success)
    throw std::runtime_error("the elastic modes at rest could not be computed (the eigensolver failed)");
  if (!(es.eigenvalues().array() > 0.0).all())
    throw std::runtime_error("the elastic modes at rest could not be computed: the lowest ω² is " +
                             util::format_number(es.eigenvalues().minCoeff(), 3) +
                             ", not > 0 (do the beam's mass and stiffness span too many orders of magnitude?)");
  r.Phi = es.eigenvectors();
  r.omega2 = es.eigenvalues();
  return r;
}

}  // namespace freeflex
