// The maneuver optimizer's plant (trajopt/maneuver_dynamics.hpp): the rigid model and,
// when asked, the elastic one beside it, their derivatives placed in z = [x0, x1, u].
#include "freeflex/trajopt/maneuver_dynamics.hpp"

#include <algorithm>
#include <stdexcept>

namespace freeflex {

ManeuverDynamics::ManeuverDynamics(const FlexibleBody& body, std::vector<int> actuators)
    : rigid_(body, std::move(actuators)) {
  build_patterns();
}

ManeuverDynamics::ManeuverDynamics(const FlexibleBody& body, std::vector<int> actuators,
                                   std::shared_ptr<const ElasticDynamics> elastic)
    : rigid_(body, std::move(actuators)), elastic_(std::move(elastic)) {
  if (elastic_ && elastic_->nu() != rigid_.nu())
    throw std::invalid_argument("maneuver dynamics: the elastic part has another actuator count");
  if (elastic_) nx_ = RigidDynamics::nx + elastic_->nx();
  build_patterns();
}

void ManeuverDynamics::build_patterns() {
  constexpr int n0 = RigidDynamics::nx;
  jac_pattern_.clear();
  hess_pattern_.clear();
  for (const auto& rc : rigid_.jacobian_pattern()) jac_pattern_.emplace_back(rc.first, zmap(rc.second));
  for (const auto& rc : rigid_.hessian_pattern()) hess_pattern_.emplace_back(zmap(rc.first), zmap(rc.second));
  if (elastic_) {
    const ElasticDynamics& el = *elastic_;
    const int n = el.n(), nx1 = el.nx();
    std::vector<int> pcols;
    for (int a : el.active_p()) pcols.push_back(pmap(a));
    for (int i = 0; i < nx1; ++i) {
      std::vector<int> cols;
      if (i <= n) {
        cols.push_back(n0 + n + 3 + i);  // θ1' = θ1', q' = q'
      } else {
        for (int c = 0; c < nx1; ++c) cols.push_back(n0 + c);
        cols.insert(cols.end(), pcols.begin(), pcols.end());
      }
      std::sort(cols.begin(), cols.end());
      for (int c : cols) jac_pattern_.emplace_back(n0 + i, c);
    }
    for (const auto& ab : el.pp_pattern()) {
      int r = pmap(ab.first), c = pmap(ab.second);
      if (r < c) std::swap(r, c);
      hess_pattern_.emplace_back(r, c);
    }
    for (int pc : pcols)
      for (int c = 0; c < nx1; ++c) {
        const int xc = n0 + c;
        hess_pattern_.emplace_back(std::max(pc, xc), std::min(pc, xc));
      }
    std::sort(hess_pattern_.begin(), hess_pattern_.end());
    hess_pattern_.erase(std::unique(hess_pattern_.begin(), hess_pattern_.end()), hess_pattern_.end());
  }
}

ManeuverDynamics::Data ManeuverDynamics::create_data() const {
  Data d;
  d.f.setZero(nx_);
  d.J.setZero(nx_, nz());
  d.H.setZero(nz(), nz());
  d.rigid = rigid_.create_data();
  if (elastic_) d.elastic = elastic_->create_data();
  return d;
}

const Eigen::VectorXd& ManeuverDynamics::calc(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                                              const Eigen::Ref<const Eigen::VectorXd>& u) const {
  constexpr int n0 = RigidDynamics::nx;
  data.f.resize(nx_);
  data.f.head<n0>() = rigid_.eval(x.head<n0>(), u);
  if (elastic_) {
    elastic_->calc(data.elastic, x(2), x(5), u, x.tail(nx_ - n0));
    data.f.tail(nx_ - n0) = data.elastic.f;
  }
  return data.f;
}

Eigen::VectorXd ManeuverDynamics::eval(const Eigen::Ref<const Eigen::VectorXd>& x,
                                       const Eigen::Ref<const Eigen::VectorXd>& u) const {
  if (!elastic_) return rigid_.eval(x, u);
  Data d = create_data();
  return calc(d, x, u);
}

void ManeuverDynamics::calc_diff(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                                 const Eigen::Ref<const Eigen::VectorXd>& u) const {
  constexpr int n0 = RigidDynamics::nx;
  const int nu = this->nu();
  rigid_.calc_diff(data.rigid, x.head<n0>(), u);
  data.f.resize(nx_);
  data.J.setZero(nx_, nz());
  data.f.head<n0>() = data.rigid.f;
  data.J.topLeftCorner<n0, n0>() = data.rigid.J.leftCols<n0>();
  data.J.block(0, nx_, n0, nu) = data.rigid.J.rightCols(nu);
  if (!elastic_) return;
  const ElasticDynamics& el = *elastic_;
  const int nx1 = el.nx();
  el.calc_diff(data.elastic, x(2), x(5), u, x.tail(nx1));
  data.f.tail(nx1) = data.elastic.f;
  data.J.block(n0, n0, nx1, nx1) = data.elastic.Jx;
  for (int a = 0; a < el.np(); ++a) data.J.block(n0, pmap(a), nx1, 1) += data.elastic.Jp.col(a);
}

const Eigen::MatrixXd& ManeuverDynamics::calc_hessian(Data& data, const Eigen::Ref<const Eigen::VectorXd>& x,
                                                      const Eigen::Ref<const Eigen::VectorXd>& u,
                                                      const Eigen::Ref<const Eigen::VectorXd>& lambda) const {
  constexpr int n0 = RigidDynamics::nx;
  const int nu = this->nu();
  const Eigen::MatrixXd& Hr = rigid_.calc_hessian(data.rigid, x.head<n0>(), u, lambda.head<n0>());
  if (!elastic_) {
    data.H = Hr;
    return data.H;
  }
  data.H.setZero(nz(), nz());
  data.H.topLeftCorner<n0, n0>() = Hr.topLeftCorner<n0, n0>();
  data.H.block(nx_, 0, nu, n0) = Hr.bottomLeftCorner(nu, n0);
  data.H.block(0, nx_, n0, nu) = Hr.topRightCorner(n0, nu);
  data.H.bottomRightCorner(nu, nu) = Hr.bottomRightCorner(nu, nu);
  const ElasticDynamics& el = *elastic_;
  const int nx1 = el.nx();
  el.calc_hessian(data.elastic, x(2), x(5), u, x.tail(nx1), lambda.tail(nx1));
  for (int a = 0; a < el.np(); ++a) {
    for (int b = 0; b < el.np(); ++b) data.H(pmap(a), pmap(b)) += data.elastic.Hpp(a, b);
    data.H.block(pmap(a), n0, 1, nx1) += data.elastic.Hpx.row(a);
    data.H.block(n0, pmap(a), nx1, 1) += data.elastic.Hpx.row(a).transpose();
  }
  return data.H;
}

}  // namespace freeflex
