// The zero-order rigid dynamics for collocation: f(x, u), its Jacobian and the contracted
// Hessian in closed form.
#include "freeflex/trajopt/rigid_dynamics.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace freeflex {

namespace {

/// Coefficients of the rigid-body Schur complement at angle θ (see the header):
/// θ'' = wᵀ G, with w = [−b/(m D); 1/D] and its θ-derivatives w1, w2.
struct Angle {
  double c, s;
  Eigen::Vector2d b, p;     // b = S(−s, c), p = S(c, s)
  Eigen::Vector3d w, w1, w2;
  Angle(double theta, double m, double S, double D) : c(std::cos(theta)), s(std::sin(theta)) {
    b << -S * s, S * c;
    p << S * c, S * s;
    const double k = S / (m * D);
    w << k * s, -k * c, 1.0 / D;
    w1 << k * c, k * s, 0.0;
    w2 << -k * s, k * c, 0.0;
  }
};

}  // namespace

RigidDynamics::RigidDynamics(const FlexibleBody& body, std::vector<int> actuators) : actuators_(std::move(actuators)) {
  const int ne = static_cast<int>(body.elements().size());
  if (actuators_.empty())
    throw std::invalid_argument("rigid dynamics: actuators is empty, expected at least one element index");
  for (std::size_t k = 0; k < actuators_.size(); ++k) {
    const int e = actuators_[k];
    if (e < 0 || e >= ne)
      throw std::invalid_argument("rigid dynamics: actuators[" + std::to_string(k) + "] = " + std::to_string(e) +
                                  ", expected an element index in [0, " + std::to_string(ne - 1) + "] (the body has " +
                                  std::to_string(ne) + " elements)");
    for (std::size_t j = 0; j < k; ++j)
      if (actuators_[j] == e)
        throw std::invalid_argument("rigid dynamics: actuators[" + std::to_string(k) + "] = " + std::to_string(e) +
                                    " repeats actuators[" + std::to_string(j) + "], expected distinct elements");
  }
  const ModalIntegrals& mi = body.integrals();
  m_ = mi.m;
  S_ = mi.S_o;
  I_ = mi.I_o;
  D_ = I_ - S_ * S_ / m_;  // rotary inertia about the mass centre
  if (!(m_ > 0.0) || !(D_ > 0.0))
    throw std::invalid_argument("rigid dynamics: the body needs m > 0 and I_o - S_o^2/m > 0");

  const int nu = this->nu();
  A_.resize(3, nu);
  B_.resize(3, nu);
  C_.resize(3, nu);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(body.n());
  const double half_pi = 0.5 * std::acos(-1.0);
  for (int k = 0; k < nu; ++k) {
    const int e = actuators_[k];
    const FlexibleBody::ForceDerivative at0 = body.element_force_derivative(e, 0.0, q0);
    const Eigen::Vector3d g0 = at0.value.head<3>(), dg0 = at0.derivative.block<3, 1>(0, 0);
    const Eigen::VectorXd g_half = body.element_force(e, half_pi, q0);
    C_.col(k) = dg0;                            // g'(0) = C
    A_.col(k) = g_half.head<3>() - C_.col(k);   // g(π/2) = A + C
    B_.col(k) = g0 - A_.col(k);                 // g(0) = A + B
    // The trigonometric form is exact for every element type at q = 0; check it anyway
    // so that a new element model cannot silently break the optimizer's derivatives.
    const double th = 1.234;
    const FlexibleBody::ForceDerivative at_th = body.element_force_derivative(e, th, q0);
    const Eigen::VectorXd& g = at_th.value;
    const Eigen::MatrixXd& d = at_th.derivative;
    const Eigen::Vector3d model = A_.col(k) + B_.col(k) * std::cos(th) + C_.col(k) * std::sin(th);
    const Eigen::Vector3d dmodel = -B_.col(k) * std::sin(th) + C_.col(k) * std::cos(th);
    const double scale = 1.0 + g.head<3>().cwiseAbs().maxCoeff();
    if ((model - g.head<3>()).cwiseAbs().maxCoeff() > 1e-12 * scale ||
        (dmodel - d.block<3, 1>(0, 0)).cwiseAbs().maxCoeff() > 1e-12 * scale)
      throw std::logic_error("rigid dynamics: element '" + body.elements()[e].name +
                             "' is not of the form A + B cos(theta) + C sin(theta) at q = 0");
  }

  for (int i = 0; i < 3; ++i) jac_pattern_.emplace_back(i, i + 3);
  for (int r = 3; r < 6; ++r) {
    jac_pattern_.emplace_back(r, 2);
    if (r < 5) jac_pattern_.emplace_back(r, 5);  // θ'' does not depend on θ'
    for (int k = 0; k < nu; ++k) jac_pattern_.emplace_back(r, nx + k);
  }
  hess_pattern_ = {{2, 2}, {5, 2}, {5, 5}};
  for (int k = 0; k < nu; ++k) hess_pattern_.emplace_back(nx + k, 2);
}

Eigen::Vector3d RigidDynamics::actuator_force(int k, double theta) const {
  return A_.col(k) + B_.col(k) * std::cos(theta) + C_.col(k) * std::sin(theta);
}

RigidDynamics::Data RigidDynamics::create_data() const {
  Data d;
  d.J.setZero(nx, nz());
  d.H.setZero(nz(), nz());
  return d;
}

RigidDynamics::Vector6d RigidDynamics::eval(const Eigen::Ref<const Eigen::VectorXd>& x,
                                            const Eigen::Ref<const Eigen::VectorXd>& u) const {
  Vector6d f;
  const Angle a(x(2), m_, S_, D_);
  const double om = x(5);
  const Eigen::Vector3d G = A_ * u + (B_ * u) * a.c + (C_ * u) * a.s;
  const double phi = a.w.dot(G);
  f.head<3>() = x.tail<3>();
  f.segment<2>(3) = (G.head<2>() + om * om * a.p - a.b * phi) / m_;
  f(5) = phi;
  return f;
}

void RigidDynamics::calc_diff(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>& u) const {
  Vector6d& f = data.f;
  Eigen::MatrixXd& J = data.J;
  J.resize(nx, nz());
  const Angle a(x(2), m_, S_, D_);
  const double om = x(5);
  const Eigen::Vector3d Bu = B_ * u, Cu = C_ * u;
  const Eigen::Vector3d G = A_ * u + Bu * a.c + Cu * a.s;
  const Eigen::Vector3d Gt = -Bu * a.s + Cu * a.c;  // ∂G/∂θ
  const double phi = a.w.dot(G);
  const double phi_t = a.w1.dot(G) + a.w.dot(Gt);
  f.head<3>() = x.tail<3>();
  f.segment<2>(3) = (G.head<2>() + om * om * a.p - a.b * phi) / m_;
  f(5) = phi;

  J.setZero();
  J(0, 3) = J(1, 4) = J(2, 5) = 1.0;
  // ∂a_R/∂θ uses b' = −p, p' = b.
  J.block<2, 1>(3, 2) = (Gt.head<2>() + om * om * a.b + a.p * phi - a.b * phi_t) / m_;
  J(5, 2) = phi_t;
  J.block<2, 1>(3, 5) = 2.0 * om * a.p / m_;
  for (int k = 0; k < nu(); ++k) {
    const Eigen::Vector3d gk = A_.col(k) + B_.col(k) * a.c + C_.col(k) * a.s;
    const double phi_u = a.w.dot(gk);
    J.block<2, 1>(3, nx + k) = (gk.head<2>() - a.b * phi_u) / m_;
    J(5, nx + k) = phi_u;
  }
}

const Eigen::MatrixXd& RigidDynamics::calc_hessian(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                                                   const Eigen::Ref<const Eigen::VectorXd>& u,
                                                   const Eigen::Ref<const Eigen::VectorXd>& lambda) const {
  Eigen::MatrixXd& H = data.H;
  H.resize(nz(), nz());
  // f(0:2) = x(3:5) is linear: only the multipliers of a_R and θ'' contribute.
  const Angle a(x(2), m_, S_, D_);
  const double om = x(5);
  const Eigen::Vector2d lR = lambda.segment<2>(3);
  const double lt = lambda(5);
  const Eigen::Vector3d Bu = B_ * u, Cu = C_ * u;
  const Eigen::Vector3d G = A_ * u + Bu * a.c + Cu * a.s;
  const Eigen::Vector3d Gt = -Bu * a.s + Cu * a.c;
  const Eigen::Vector3d Gtt = -Bu * a.c - Cu * a.s;  // g'' = −(g − A)
  const double phi = a.w.dot(G);
  const double phi_t = a.w1.dot(G) + a.w.dot(Gt);
  const double phi_tt = a.w2.dot(G) + 2.0 * a.w1.dot(Gt) + a.w.dot(Gtt);
  const Eigen::Vector2d aR_tt = (Gtt.head<2>() - om * om * a.p + a.b * phi + 2.0 * a.p * phi_t - a.b * phi_tt) / m_;

  H.setZero();
  H(2, 2) = lR.dot(aR_tt) + lt * phi_tt;
  H(5, 2) = H(2, 5) = lR.dot(2.0 * om * a.b / m_);
  H(5, 5) = lR.dot(2.0 * a.p / m_);
  for (int k = 0; k < nu(); ++k) {
    const Eigen::Vector3d gk = A_.col(k) + B_.col(k) * a.c + C_.col(k) * a.s;
    const Eigen::Vector3d gtk = -B_.col(k) * a.s + C_.col(k) * a.c;
    const double phi_u = a.w.dot(gk);
    const double phi_tu = a.w1.dot(gk) + a.w.dot(gtk);
    const Eigen::Vector2d aR_tu = (gtk.head<2>() + a.p * phi_u - a.b * phi_tu) / m_;
    H(nx + k, 2) = H(2, nx + k) = lR.dot(aR_tu) + lt * phi_tu;
  }
  return H;
}

}  // namespace freeflex
