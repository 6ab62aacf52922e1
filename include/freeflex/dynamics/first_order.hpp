#pragma once
// First-order (LTV) model, eq. 7.1-7.3: the full model linearized about a rigid
// trajectory (R0, θ0) with q = 0 and nominal commands u0(t). With δz = [R1, θ1, q]:
//   𝕄0(t) δz'' = Kt(t) δz + Ct(t) δz' + Gu(t) u1 + r0(t)
// and in state-space form, x1 = [δz, δz']:  x1' = A(t) x1 + B(t) u1 + g(t).
#include <functional>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/dynamics/zero_order.hpp"

namespace freeflex {

/// Nominal commands of every force element at an instant: a callback that writes them
/// into the buffer it is handed (one entry per element).
using CommandFunction = std::function<void(const Instant&, Eigen::Ref<Eigen::VectorXd>)>;

/// x' = A x + B u + g at one instant (sizes n x n, n x m, n).
struct StateSpace {
  Eigen::MatrixXd A, B;
  Eigen::VectorXd g;
};

class FirstOrderModel {
 public:
  /// Implicit form at one instant (eq. 7.1).
  struct Implicit {
    Eigen::MatrixXd M0;  ///< 𝕄(θ0, 0)
    Eigen::MatrixXd Kt;  ///< -∂(residual)/∂z
    Eigen::MatrixXd Ct;  ///< -∂(residual)/∂z'
    Eigen::MatrixXd Gu;  ///< generalized force per unit command of each input
    Eigen::VectorXd r0;  ///< residual of the full model on the nominal motion (the forcing)
    double theta0 = 0.0; ///< the nominal angle θ0 [rad]: 𝕄0 = 𝕄(θ0, 0)
  };

  /// Workspace of one thread of evaluation (make one with create_data()): results and
  /// scratch. The model is const and may serve several threads, each with its own Data.
  struct Data {
    StateSpace state_space;  ///< from the last state_space()
    Eigen::VectorXd x1_dot;  ///< from the last rhs()
    Eigen::VectorXd xq_dot;  ///< from the last prescribed_rhs()
    Eigen::VectorXd q, q0, u0, f, dG, x1;  // scratch of rhs()
    Eigen::Matrix2d C;
    Eigen::MatrixXd X, Y;  // scratch of state_space()
    Implicit implicit;     ///< from the last implicit_form(data, at) (state_space() fills it)
    Eigen::MatrixXd Kr, Cr;  // scratch of implicit_form()
    Eigen::VectorXd zdd0, M0zdd0, u_nominal, q_zero;
  };

  /// `inputs` are the element indices whose commands u1 perturb (the actuators); the
  /// trajectory and command function must outlive the model.
  FirstOrderModel(const FlexibleBody& body, const RigidTrajectory& nominal, CommandFunction nominal_commands,
                  std::vector<int> inputs);

  const FlexibleBody& body() const { return body_; }
  const RigidTrajectory& nominal() const { return nominal_; }
  int state_size() const { return 2 * body_.dofs(); }
  int input_size() const { return static_cast<int>(inputs_.size()); }
  const std::vector<int>& inputs() const { return inputs_; }

  Data create_data() const;

  /// The implicit form at one instant, into data.implicit (its matrices reused from call
  /// to call; only the force derivative allocates).
  const Implicit& implicit_form(Data& data, const Instant& at) const;
  /// The same, returned (allocates a workspace: for one-off use).
  Implicit implicit_form(const Instant& at) const;
  /// A(t), B(t), g(t) of eq. 7.3, into data.state_space.
  const StateSpace& state_space(Data& data, const Instant& at) const;
  /// The same, returned (allocates a workspace: for one-off use).
  StateSpace state_space(const Instant& at) const;
  /// x1' = A x1 + B u1 + g into data.x1_dot, without forming A: the products of eq. 7.1
  /// term by term and one solve with 𝕄0(θ0) = T 𝕄0(0) Tᵀ, T = blockdiag(C(θ0), 1, I), by
  /// the kept inverse of 𝕄0(0). u1 has input_size() entries (or none: zero).
  const Eigen::VectorXd& rhs(Data& data, const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1,
                             const Eigen::Ref<const Eigen::VectorXd>& u1) const;
  /// Prescribed rigid motion (docs/theory.md eq. 14.10): the nominal trajectory is the
  /// motion itself (R1 = θ1 = 0), and only the q rows of eq. 7.1 remain,
  /// M q'' = f_q(q, q'). xq = [q, q'] (2n); returns [q', q''] in data.xq_dot.
  const Eigen::VectorXd& prescribed_rhs(Data& data, const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& xq,
                                        const Eigen::Ref<const Eigen::VectorXd>& u1) const;

 private:
  /// The right-hand side of eq. 7.1 before the mass solve, into data.f; returns C(θ0).
  const Eigen::Matrix2d& forces(Data& data, const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1,
                                const Eigen::Ref<const Eigen::VectorXd>& u1) const;
  const FlexibleBody& body_;
  const RigidTrajectory& nominal_;
  CommandFunction commands_;
  std::vector<int> inputs_;
  Eigen::MatrixXd rest_inverse_;  // 𝕄0(0)⁻¹, the mass matrix at θ = 0
  Eigen::MatrixXd mq_inverse_;    // M⁻¹ (prescribed motion)
};

}  // namespace freeflex
