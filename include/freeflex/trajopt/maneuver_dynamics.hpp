#pragma once
// The plant of the maneuver optimizer: the zero-order rigid motion (trajopt/rigid_dynamics.hpp)
// alone, or with the first-order elastic motion about it (trajopt/elastic_dynamics.hpp).
//
//   x = [x0 (6), x1 (0 or 4 + 2n)],  x0 = [Rx, Ry, θ, Rx', Ry', θ'],  z = [x, u]
//   f(x, u) = [f0(x0, u); f1(θ, θ', u, x1)]
//
// With the elastic part off every value is the rigid model's, computed by it alone.
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/trajopt/elastic_dynamics.hpp"
#include "freeflex/trajopt/rigid_dynamics.hpp"

namespace freeflex {

class ManeuverDynamics {
 public:
  /// Rigid only.
  ManeuverDynamics(const FlexibleBody& body, std::vector<int> actuators);
  /// Rigid and elastic (`elastic` built for the same body and actuators).
  ManeuverDynamics(const FlexibleBody& body, std::vector<int> actuators, std::shared_ptr<const ElasticDynamics> elastic);

  const RigidDynamics& rigid() const { return rigid_; }
  /// The elastic part, or null.
  const ElasticDynamics* elastic() const { return elastic_.get(); }
  int nx() const { return nx_; }
  int nu() const { return rigid_.nu(); }
  int nz() const { return nx_ + nu(); }

  struct Data {
    Eigen::VectorXd f;  ///< f(x, u)
    Eigen::MatrixXd J;  ///< [∂f/∂x, ∂f/∂u] (nx x nz)
    Eigen::MatrixXd H;  ///< Σ λ_i ∂²f_i/∂z² (nz x nz)
    RigidDynamics::Data rigid;
    ElasticDynamics::Data elastic;
  };
  Data create_data() const;

  /// f into data.f.
  const Eigen::VectorXd& calc(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                              const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// f(x, u), allocating (one-off evaluations).
  Eigen::VectorXd eval(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// f and J into data (every entry of J written).
  void calc_diff(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                 const Eigen::Ref<const Eigen::VectorXd>& u) const;
  /// H into data.H (every entry written).
  const Eigen::MatrixXd& calc_hessian(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                                      const Eigen::Ref<const Eigen::VectorXd>& u,
                                      const Eigen::Ref<const Eigen::VectorXd>& lambda) const;

  /// Structural nonzeros of J (row, col) and of H's lower triangle, over z = [x, u].
  const std::vector<std::pair<int, int>>& jacobian_pattern() const { return jac_pattern_; }
  const std::vector<std::pair<int, int>>& hessian_pattern() const { return hess_pattern_; }

 private:
  /// Index in z of rigid z index i (u moves behind x1).
  int zmap(int i) const { return i < RigidDynamics::nx ? i : i + nx_ - RigidDynamics::nx; }
  /// Index in z of p = (θ, θ', u) entry a.
  int pmap(int a) const { return a == 0 ? 2 : a == 1 ? 5 : nx_ + a - 2; }
  void build_patterns();

  RigidDynamics rigid_;
  std::shared_ptr<const ElasticDynamics> elastic_;
  int nx_ = RigidDynamics::nx;
  std::vector<std::pair<int, int>> jac_pattern_, hess_pattern_;
};

}  // namespace freeflex
