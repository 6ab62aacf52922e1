#pragma once
// The zero-order (rigid) equations (docs/theory.md eq. 6.3 at q = 0) as a first-order
// system with controls, together with their exact first and second derivatives, for
// direct collocation.
//
//   x = [Rx, Ry, θ, Rx', Ry', θ'] (SI, radians),  u = commands of the chosen actuators
//   f(x, u) = [x(3:5); a],   𝕄_rr(θ) a = [G_R(θ, u) + θ'² S_o (cos θ, sin θ); G_θ(θ, u)]
//   G(θ, u) = Σ_k u_k g_k(θ),  g_k = rows 0..2 of FlexibleBody::element_force at q = 0.
//
// Elimination of R'' (the Schur complement of m I₂ in 𝕄_rr) gives closed forms:
//   b(θ) = S_o (−sin θ, cos θ),  p(θ) = S_o (cos θ, sin θ) = −b',  D = I_o − S_o²/m > 0
//   θ'' = φ(θ, u) = (G_θ − bᵀ G_R / m) / D           (no θ' term: bᵀ p = 0)
//   R'' = (G_R + θ'² p − b φ) / m
// At q = 0 every element's g_k has the form A_k + B_k cos θ + C_k sin θ (a force has a
// fixed inertial direction and a moment arm that turns, a thruster the reverse, a torque
// is constant), so g_k'' = −(g_k − A_k). The coefficients are read from element_force
// at construction, which makes FlexibleBody the single source of the element models.
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"

namespace freeflex {

class RigidDynamics {
 public:
  static constexpr int nx = 6;
  using Vector6d = Eigen::Matrix<double, 6, 1>;

  /// `actuators[k]` is the index in body.elements() commanded by u_k. Throws
  /// std::invalid_argument for an empty list, an index out of range or a repeated index.
  RigidDynamics(const FlexibleBody& body, std::vector<int> actuators);

  int nu() const { return static_cast<int>(actuators_.size()); }
  /// Size of one (x, u) block: 6 + nu.
  int nz() const { return nx + nu(); }
  const std::vector<int>& actuators() const { return actuators_; }
  double mass() const { return m_; }
  double S_o() const { return S_; }
  double I_o() const { return I_; }

  /// Generalized force [F_X, F_Y, M_o] of actuator k per unit command at q = 0.
  Eigen::Vector3d actuator_force(int k, double theta) const;

  /// Results of one evaluation (make one with create_data()); the model is const and
  /// serves any number of threads, each with its own Data.
  struct Data {
    Vector6d f = Vector6d::Zero();  ///< f(x, u), from calc() and calc_diff()
    Eigen::MatrixXd J;              ///< [∂f/∂x, ∂f/∂u] (6 x nz()), from calc_diff()
    Eigen::MatrixXd H;              ///< Σ_i λ_i ∂²f_i/∂(x,u)² (nz() x nz(), symmetric), from calc_hessian()
  };
  Data create_data() const;

  /// f(x, u). x has 6 entries, u has nu().
  Vector6d eval(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// f(x, u) and J = [∂f/∂x, ∂f/∂u] into data.f, data.J (every entry of J written).
  void calc_diff(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                 const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// H = Σ_i lambda_i ∂²f_i/∂(x,u)² into data.H (every entry written).
  const Eigen::MatrixXd& calc_hessian(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                                      const Eigen::Ref<const Eigen::VectorXd>& u,
                                      const Eigen::Ref<const Eigen::VectorXd>& lambda) const;

  /// Structural nonzeros of J, (row, col), row-major order. Entries outside are zero for
  /// every (x, u).
  const std::vector<std::pair<int, int>>& jacobian_pattern() const { return jac_pattern_; }
  /// Structural nonzeros of the lower triangle (row >= col) of H for every lambda.
  const std::vector<std::pair<int, int>>& hessian_pattern() const { return hess_pattern_; }

 private:
  std::vector<int> actuators_;
  double m_ = 0.0, S_ = 0.0, I_ = 0.0, D_ = 0.0;
  Eigen::Matrix<double, 3, Eigen::Dynamic> A_, B_, C_;  // g_k = A_k + B_k cos θ + C_k sin θ
  std::vector<std::pair<int, int>> jac_pattern_, hess_pattern_;
};

}  // namespace freeflex
