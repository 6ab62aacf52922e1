// Figures of merit of a response: residual and mean vibration energy, tip deflection and
// its settling, final rigid errors, control effort.
#include "freeflex/control/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace freeflex {

ResponseMetrics response_metrics(const FlexibleBody& body, const Eigen::Ref<const Eigen::VectorXd>& t,
                                 const Eigen::Ref<const Eigen::MatrixXd>& z,
                                 const Eigen::Ref<const Eigen::MatrixXd>& z_dot,
                                 const Eigen::Ref<const Eigen::MatrixXd>& commands, const MetricTargets& targets) {
  const int T = static_cast<int>(t.size()), N = body.dofs(), n = body.n();
  auto fail = [](const std::string& what) { throw std::invalid_argument("response_metrics: " + what); };
  if (T < 1) fail("expected at least one sample, got none");
  if (z.rows() != T || z.cols() != N)
    fail("expected z of size " + std::to_string(T) + " x " + std::to_string(N) + ", got " + std::to_string(z.rows()) +
         " x " + std::to_string(z.cols()));
  if (z_dot.rows() != T || z_dot.cols() != N)
    fail("expected z_dot of size " + std::to_string(T) + " x " + std::to_string(N) + ", got " +
         std::to_string(z_dot.rows()) + " x " + std::to_string(z_dot.cols()));
  if (commands.cols() > 0 && commands.rows() != T)
    fail("expected one row of commands per time (" + std::to_string(T) + "), got " + std::to_string(commands.rows()));
  for (int i = 1; i < T; ++i)
    if (!(t(i) > t(i - 1))) fail("times must be strictly ascending (index " + std::to_string(i) + ")");
  if (!(targets.energy_window_s > 0.0)) fail("energy_window_s must be > 0");

  ResponseMetrics r;
  const Eigen::VectorXd qT = z.row(T - 1).tail(n).transpose(), qdT = z_dot.row(T - 1).tail(n).transpose();
  r.residual_vibration_energy_J = body.vibration_energy(qT, qdT);
  {
    auto energy = [&](int i) {
      return body.vibration_energy(z.row(i).tail(n).transpose(), z_dot.row(i).tail(n).transpose());
    };
    int i0 = T - 1;
    while (i0 > 0 && t(i0 - 1) >= t(T - 1) - targets.energy_window_s) --i0;
    if (i0 == T - 1) {
      r.mean_vibration_energy_J = r.residual_vibration_energy_J;
    } else {
      double integral = 0.0, e_prev = energy(i0);
      for (int i = i0 + 1; i < T; ++i) {
        const double e = energy(i);
        integral += 0.5 * (t(i) - t(i - 1)) * (e + e_prev);
        e_prev = e;
      }
      r.mean_vibration_energy_J = integral / (t(T - 1) - t(i0));
    }
  }
  const Eigen::RowVectorXd phi_l = body.basis().value(body.beam().x_left());
  const Eigen::RowVectorXd phi_r = body.basis().value(body.beam().x_right());
  Eigen::VectorXd tip(T);
  for (int i = 0; i < T; ++i) {
    const Eigen::VectorXd q = z.row(i).tail(n).transpose();
    tip(i) = std::max(std::abs(phi_l.dot(q)), std::abs(phi_r.dot(q)));
  }
  r.peak_tip_deflection_m = tip.maxCoeff();
  r.tip_settling_time_s = t(0);
  r.settled = true;
  if (r.peak_tip_deflection_m > 0.0) {
    const double band = 0.01 * r.peak_tip_deflection_m;
    for (int i = T - 1; i >= 0; --i)
      if (tip(i) > band) {
        r.tip_settling_time_s = t(i);
        r.settled = i < T - 1;
        break;
      }
  }
  r.final_position_error_m = (z.row(T - 1).head<2>().transpose() - targets.R_target).norm();
  r.final_attitude_error_rad = std::abs(z(T - 1, 2) - targets.theta_target);
  if (commands.cols() > 0) {
    for (int i = 1; i < T; ++i)
      r.control_effort += 0.5 * (t(i) - t(i - 1)) * (commands.row(i).squaredNorm() + commands.row(i - 1).squaredNorm());
    r.peak_command = commands.cwiseAbs().maxCoeff();
  }
  return r;
}

}  // namespace freeflex
