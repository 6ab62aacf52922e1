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

/// Nominal commands of every force element at an instant.
using CommandFunction = std::function<void(const Instant&, Eigen::Ref<Eigen::VectorXd>)>;

class FirstOrderModel {
 public:
  /// Implicit form at one instant (eq. 7.1).
  struct Implicit {
    Eigen::MatrixXd M0;  ///< 𝕄(θ0, 0)
    Eigen::MatrixXd Kt;  ///< -∂(residual)/∂z
    Eigen::MatrixXd Ct;  ///< -∂(residual)/∂z'
    Eigen::MatrixXd Gu;  ///< generalized force per unit command of each input
    Eigen::VectorXd r0;  ///< residual of the full model on the nominal motion (the forcing)
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

  void implicit_form(const Instant& at, Implicit& out) const;
  /// A(t), B(t), g(t) of eq. 7.3.
  void state_space(const Instant& at, Eigen::MatrixXd& A, Eigen::MatrixXd& B, Eigen::VectorXd& g) const;
  /// x1' = A x1 + B u1 + g without forming A: the products of eq. 7.1 term by term and
  /// one solve with 𝕄0(θ0) = T 𝕄0(0) Tᵀ, T = blockdiag(C(θ0), 1, I), by the kept inverse
  /// of 𝕄0(0).
  void rhs(const Instant& at, const Eigen::Ref<const Eigen::VectorXd>& x1, const Eigen::Ref<const Eigen::VectorXd>& u1,
           Eigen::Ref<Eigen::VectorXd> x1_dot) const;

 private:
  const FlexibleBody& body_;
  const RigidTrajectory& nominal_;
  CommandFunction commands_;
  std::vector<int> inputs_;
  Eigen::MatrixXd rest_inverse_;  // 𝕄0(0)⁻¹, the mass matrix at θ = 0
};

}  // namespace freeflex
