// The workbench's chain from a downstream program, public headers only: the minimum-
// energy slew of designs/suppress_slew.toml, TV-LQR about it, the full nonlinear model
// in closed loop against the open loop. Prints the residual vibration energies; exits 1
// unless the feedback leaves at least 1000x less.
#include <cmath>
#include <cstdio>

#include "freeflex/freeflex.hpp"

using namespace freeflex;

int main() {
  const FlexibleBody body(Beam(BeamProperties::uniform(1.0, 1.0, 1.0)), 6,
                          {{"left", ForceElement::Type::Thruster, 0.0, {0.0, 1.0}, false},
                           {"right", ForceElement::Type::Thruster, 1.0, {0.0, 1.0}, false}});
  ManeuverProblem slew;
  slew.actuators = {0, 1};
  slew.u_min = Eigen::Vector2d(-1.0, -1.0);
  slew.u_max = Eigen::Vector2d(1.0, 1.0);
  slew.x_final << 1.0, 0.5, std::acos(-1.0) / 2, 0.0, 0.0, 0.0;
  slew.duration_s = 3.0;
  const TrajoptResult opt = solve_maneuver(body, slew, TrajoptOptions{});
  if (!opt.ok()) return std::printf("slew failed: %s\n", opt.message.c_str()), 1;
  SuppressionProblem p;
  p.loads.profiles.assign(2, std::nullopt);
  p.maneuver = flown_maneuver(opt, slew);
  p.actuators = {0, 1};
  p.limits = Eigen::Vector2d(1.0, 1.0);
  p.Q = vibration_weight(body, 10.0, 10.0, 1.0);
  p.R = Eigen::Matrix2d::Identity();
  p.horizon_s = p.until_s = 5.0;
  const SuppressionResult r = suppress_vibration(body, p);
  if (!r.ok()) return std::printf("chain failed: %s\n", r.message.c_str()), 1;
  const int n = body.n();
  auto energy = [&](const Eigen::MatrixXd& z, const Eigen::MatrixXd& zd) {
    const Eigen::Index last = z.rows() - 1;
    return body.vibration_energy(z.row(last).tail(n).transpose(), zd.row(last).tail(n).transpose());
  };
  const double open = energy(r.open_loop_full.z, r.open_loop_full.z_dot);
  const double closed = energy(r.closed_loop_full.z, r.closed_loop_full.z_dot);
  std::printf("slew J = %.4f N^2 s; E_vib(5 s) open loop %.3e J, TV-LQR %.3e J\n", opt.objective, open, closed);
  return closed * 1000.0 < open ? 0 : 1;
}
