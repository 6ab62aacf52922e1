// The first-order (LTV) model about a rigid trajectory (eq. 7.1-7.3): implicit form,
// state-space matrices and the term-by-term right-hand side.
#include "freeflex/dynamics/first_order.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "dynamics/body_kernels.hpp"
#include "planar.hpp"

namespace freeflex {
namespace {
using planar::rot;

/// The nominal motion at one instant and the rotated vectors eq. 7.1 needs.
struct Frame {
  double th, thd, thdd;
  Eigen::Vector2d Rdd;
  Eigen::Matrix2d C;
  Eigen::Vector2d Ce1, Ce2, CJe2, Cs0, CJs0;  // C e1, C e2, C J e2 = -C e1, C s0, C J s0
  Eigen::Vector3d acc;
};

Frame frame_at(const RigidTrajectory& nominal, const Instant& at, double S_o) {
  const RigidState r = nominal.at(at);
  Frame f;
  f.th = r.pos(2);
  f.thd = r.vel(2);
  f.thdd = r.acc(2);
  f.Rdd = r.acc.head<2>();
  f.acc = r.acc;
  f.C = rot(f.th);
  f.Ce1 = f.C.col(0);
  f.Ce2 = f.C.col(1);
  f.CJe2 = -f.Ce1;
  f.Cs0 = S_o * f.Ce1;
  f.CJs0 = S_o * f.Ce2;
  return f;
}
}  // namespace

FirstOrderModel::FirstOrderModel(const FlexibleBody& body, const RigidTrajectory& nominal,
                                 CommandFunction nominal_commands, std::vector<int> inputs)
    : body_(body), nominal_(nominal), commands_(std::move(nominal_commands)), inputs_(std::move(inputs)) {
  const int ne = static_cast<int>(body_.elements().size());
  for (int i : inputs_)
    if (i < 0 || i >= ne)
      throw std::invalid_argument("first-order model: input index " + std::to_string(i) + " is not an element (0.." +
                                  std::to_string(ne - 1) + ")");
  const Eigen::MatrixXd M0 = body_.mass_matrix(0.0, Eigen::VectorXd::Zero(body_.n()));
  // symmetric positive definite and well conditioned (the basis is orthogonal in M): its
  // inverse, formed once, makes every solve one matrix-vector product
  rest_inverse_ = M0.llt().solve(Eigen::MatrixXd::Identity(body_.dofs(), body_.dofs()));
  mq_inverse_ = body_.integrals().M.llt().solve(Eigen::MatrixXd::Identity(body_.n(), body_.n()));
}

FirstOrderModel::Data FirstOrderModel::create_data() const { return Data{}; }

const FirstOrderModel::Implicit& FirstOrderModel::implicit_form(Data& data, const Instant& at) const {
  // Writes into the workspace's matrices, whose sizes stay the same from call to call (the
  // TV-LQR sweep evaluates this at every right-hand side; docs/benchmarks.md): after the
  // first call only the force derivative allocates (and, with geometric stiffening, the
  // mass matrix's scratch).
  Implicit& o = data.implicit;
  const ModalIntegrals& mi = body_.integrals();
  const int n = body_.n(), N = body_.dofs();
  const Frame fr = frame_at(nominal_, at, mi.S_o);
  const double th = fr.th, thd = fr.thd, thdd = fr.thdd;
  const Eigen::Vector2d& Rdd = fr.Rdd;
  data.q_zero.setZero(n);
  const Eigen::VectorXd& q0 = data.q_zero;

  Eigen::VectorXd& u0 = data.u_nominal;
  u0.resize(static_cast<Eigen::Index>(body_.elements().size()));
  commands_(at, u0);
  const FlexibleBody::ForceDerivative force = body_.generalized_force_derivative(th, q0, u0);
  const Eigen::VectorXd& G = force.value;
  const Eigen::MatrixXd& dG = force.derivative;

  body_.mass_matrix_into(th, q0, o.M0);

  // ∂(residual)/∂z at the nominal motion (eq. 7.1); columns Rx, Ry do not appear.
  Eigen::MatrixXd& Kr = data.Kr;
  Kr.setZero(N, N);
  Kr.block<2, 1>(0, 2) = -thdd * fr.Cs0 - thd * thd * fr.CJs0;
  Kr(2, 2) = -Rdd.dot(fr.Cs0);
  Kr.block(3, 2, n, 1) = -mi.Phi_bar.transpose() * fr.Ce1.dot(Rdd);
  Kr.block(0, 3, 2, n).noalias() = (thdd * fr.CJe2 - thd * thd * fr.Ce2) * mi.Phi_bar;
  Kr.block(2, 3, 1, n) = Rdd.dot(fr.CJe2) * mi.Phi_bar;
  Kr.bottomRightCorner(n, n) = mi.K - thd * thd * mi.M;
  if (body_.geometric_stiffening())  // eq. 14.9: the tension the nominal motion sets up
    Kr.bottomRightCorner(n, n) += thd * thd * mi.G_c - fr.Ce1.dot(Rdd) * mi.H_bar;
  Kr.middleCols(2, 1 + n) -= dG;  // configuration-dependent loads (eq. 14.7 included)

  // ∂(residual)/∂z'
  Eigen::MatrixXd& Cr = data.Cr;
  Cr.setZero(N, N);
  Cr.block<2, 1>(0, 2) = -2.0 * thd * fr.Cs0;
  Cr.block(0, 3, 2, n).noalias() = 2.0 * thd * fr.CJe2 * mi.Phi_bar;
  if (body_.damped()) Cr += body_.damping();

  o.Kt = -Kr;
  o.Ct = -Cr;
  o.Gu.resize(N, input_size());
  for (int k = 0; k < input_size(); ++k) body_.element_force_into(inputs_[k], th, q0, o.Gu.col(k));
  // r0 = G - 𝕄0 z0'' - h(z0, z0'): its q rows are the forcing of the vibration; its rigid
  // rows vanish when the trajectory satisfies eq. 6.3 exactly.
  Eigen::VectorXd& zdd0 = data.zdd0;
  zdd0.setZero(N);
  zdd0.head<3>() = fr.acc;
  data.M0zdd0.noalias() = o.M0 * zdd0;
  o.r0 = G - data.M0zdd0;
  o.r0.head<2>() += thd * thd * fr.Cs0;
  o.theta0 = th;
  return o;
}

FirstOrderModel::Implicit FirstOrderModel::implicit_form(const Instant& at) const {
  Data data = create_data();
  return implicit_form(data, at);
}

const StateSpace& FirstOrderModel::state_space(Data& data, const Instant& at) const {
  const int N = body_.dofs(), m = input_size();
  const Implicit& o = implicit_form(data, at);
  // 𝕄0(θ0)⁻¹ X = T 𝕄0(0)⁻¹ Tᵀ X with T = blockdiag(C(θ0), 1, I), as in rhs(): one product
  // with the inverse formed once (a factorization and its solves at every instant took a
  // sixth of a TV-LQR sweep's instructions at NOA 6; docs/benchmarks.md)
  Eigen::MatrixXd& X = data.X;
  X.resize(N, 2 * N + m + 1);
  X.leftCols(N) = o.Kt;
  X.middleCols(N, N) = o.Ct;
  X.middleCols(2 * N, m) = o.Gu;
  X.col(2 * N + m) = o.r0;
  const Eigen::Matrix2d C = rot(o.theta0);
  for (Eigen::Index j = 0; j < X.cols(); ++j) {
    const Eigen::Vector2d v = C.transpose() * X.col(j).head<2>();
    X.col(j).head<2>() = v;
  }
  Eigen::MatrixXd& Y = data.Y;
  Y.noalias() = rest_inverse_ * X;
  for (Eigen::Index j = 0; j < Y.cols(); ++j) {
    const Eigen::Vector2d v = C * Y.col(j).head<2>();
    Y.col(j).head<2>() = v;
  }
  Eigen::MatrixXd& A = data.state_space.A;
  Eigen::MatrixXd& B = data.state_space.B;
  Eigen::VectorXd& g = data.state_space.g;
  A.resize(2 * N, 2 * N);
  B.resize(2 * N, m);
  g.resize(2 * N);
  A.topLeftCorner(N, N).setZero();
  A.topRightCorner(N, N).setIdentity();
  B.topRows(N).setZero();
  g.head(N).setZero();
  A.bottomRows(N) = Y.leftCols(2 * N);
  B.bottomRows(N) = Y.middleCols(2 * N, m);
  g.tail(N) = Y.col(2 * N + m);
  return data.state_space;
}

StateSpace FirstOrderModel::state_space(const Instant& at) const {
  Data data = create_data();
  return state_space(data, at);
}

const Eigen::VectorXd& FirstOrderModel::rhs(Data& w, const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1,
                                            const Eigen::Ref<const Eigen::VectorXd>& u1) const {
  // After the first call with a workspace the right-hand side allocates nothing (it runs
  // ~10⁴ times per simulated second).
  const int N = body_.dofs();
  const Eigen::Matrix2d& C = forces(w, at, x1, u1);
  Eigen::VectorXd& f = w.f;
  // 𝕄0(θ0)⁻¹ f = T 𝕄0(0)⁻¹ Tᵀ f
  f.head<2>() = C.transpose() * f.head<2>();
  Eigen::VectorXd& x1_dot = w.x1_dot;
  x1_dot.resize(2 * N);
  x1_dot.head(N) = x1.tail(N);
  auto z1dd = x1_dot.tail(N);
  z1dd.noalias() = rest_inverse_.lazyProduct(f);  // coefficient-wise: cheaper at these sizes
  const Eigen::Vector2d a = z1dd.head<2>();
  z1dd.head<2>() = C * a;
  return x1_dot;
}

const Eigen::VectorXd& FirstOrderModel::prescribed_rhs(Data& w, const Instant& at,
                                                       const Eigen::Ref<const Eigen::VectorXd>& xq,
                                                       const Eigen::Ref<const Eigen::VectorXd>& u1) const {
  // eq. 14.10: the q rows of eq. 7.1 with R1 = θ1 = 0, M q'' = f_q
  const int n = body_.n(), N = body_.dofs();
  w.x1.setZero(2 * N);
  w.x1.segment(3, n) = xq.head(n);
  w.x1.tail(n) = xq.tail(n);
  forces(w, at, w.x1, u1);
  w.xq_dot.resize(2 * n);
  w.xq_dot.head(n) = xq.tail(n);
  w.xq_dot.tail(n).noalias() = mq_inverse_ * w.f.tail(n);
  return w.xq_dot;
}

const Eigen::Matrix2d& FirstOrderModel::forces(Data& w, const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1,
                                               const Eigen::Ref<const Eigen::VectorXd>& u1) const {
  const ModalIntegrals& mi = body_.integrals();
  const int n = body_.n(), N = body_.dofs();
  const Frame fr = frame_at(nominal_, at, mi.S_o);
  const double th = fr.th, thd = fr.thd, thdd = fr.thdd;
  const Eigen::Vector2d& Rdd = fr.Rdd;
  const Eigen::Matrix2d& C = fr.C;
  const Eigen::Vector2d &Ce1 = fr.Ce1, &Ce2 = fr.Ce2, &CJe2 = fr.CJe2, &Cs0 = fr.Cs0, &CJs0 = fr.CJs0;
  const double th1 = x1(2), th1d = x1(N + 2);
  w.q = x1.segment(3, n);
  const auto qd = x1.tail(n);
  const double Pq = mi.Phi_bar.dot(w.q), Pqd = mi.Phi_bar.dot(qd);

  // Loads at (θ0, 0) and their change along (θ1, q): G and dG·[θ1; q].
  w.u0.resize(static_cast<Eigen::Index>(body_.elements().size()));
  w.f.setZero(N);
  w.dG.setZero(N);
  w.q0.setZero(n);
  Eigen::VectorXd& f = w.f;
  commands_(at, w.u0);
  for (int e = 0; e < w.u0.size(); ++e)
    if (w.u0(e) != 0.0) detail::add_element_force(body_, e, th, w.q0, w.u0(e), f, th1, &w.q, &w.dG);
  for (int k = 0; k < u1.size(); ++k)
    if (u1(k) != 0.0) detail::add_element_force(body_, inputs_[k], th, w.q0, u1(k), f);
  f += w.dG;
  // r0 - Kr δz - Cr δz' (eq. 7.1), row block by row block
  f.head<2>() += thd * thd * Cs0 - (mi.m * Rdd + thdd * CJs0)                     // r0
                 + (thdd * Cs0 + thd * thd * CJs0) * th1 - (thdd * CJe2 - thd * thd * Ce2) * Pq
                 + 2.0 * thd * Cs0 * th1d - 2.0 * thd * CJe2 * Pqd;
  f(2) += -(CJs0.dot(Rdd) + mi.I_o * thdd) + Rdd.dot(Cs0) * th1 - Rdd.dot(CJe2) * Pq;
  auto fq = f.tail(n);
  fq += -(mi.Phi_bar.transpose() * Ce2.dot(Rdd) + mi.Phi_tilde.transpose() * thdd) +
        mi.Phi_bar.transpose() * (Ce1.dot(Rdd) * th1);
  fq.noalias() -= mi.K * w.q;
  fq.noalias() += (thd * thd) * mi.M * w.q;
  if (body_.geometric_stiffening()) {  // eq. 14.9
    fq.noalias() -= (thd * thd) * mi.G_c * w.q;
    fq.noalias() += Ce1.dot(Rdd) * mi.H_bar * w.q;
  }
  if (body_.damped()) f.noalias() -= body_.damping() * x1.tail(N);
  w.C = C;
  return w.C;
}

}  // namespace freeflex
