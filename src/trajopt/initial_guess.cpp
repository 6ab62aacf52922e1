// Starting points for the collocation NLP (trajopt/collocation.hpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "freeflex/trajopt/collocation.hpp"

namespace freeflex {

namespace {

constexpr int nx = RigidDynamics::nx;
using Vector6d = Eigen::Matrix<double, 6, 1>;

Eigen::VectorXd checked_control(const InitialGuess& guess, double t, int nu) {
  Eigen::VectorXd u = guess.control(t);
  if (u.size() != nu)
    throw std::invalid_argument("initial guess: control(" + std::to_string(t) + ") has " + std::to_string(u.size()) +
                                " entries, expected " + std::to_string(nu) + " (one per actuator)");
  return u;
}

}  // namespace

Eigen::VectorXd initial_point(const CollocationNlp& nlp, const InitialGuess& guess) {
  const ManeuverProblem& p = nlp.problem();
  const RigidDynamics& dyn = nlp.dynamics();
  const int nu = dyn.nu(), P = nlp.num_points();
  if (guess.solution && guess.solution->dynamics().nu() != nu)
    throw std::invalid_argument("initial guess: solution has " + std::to_string(guess.solution->dynamics().nu()) +
                                " actuators, expected " + std::to_string(nu));

  double T = p.duration_s;
  if (guess.solution && p.free_time) T = guess.solution->t_end() - guess.solution->t_begin();
  if (p.free_time) T = std::clamp(T, p.t_min_s, p.t_max_s);

  auto control = [&](double t) -> Eigen::VectorXd {
    return checked_control(guess, t, nu).cwiseMax(p.u_min).cwiseMin(p.u_max);
  };
  Eigen::VectorXd w = Eigen::VectorXd::Zero(nlp.num_variables());
  Vector6d x_prev = p.x_initial;
  double t_prev = 0.0;
  for (int j = 0; j < P; ++j) {
    const double tau = nlp.point_fraction(j), t = tau * T;
    Vector6d x;
    Eigen::VectorXd u;
    if (guess.solution) {
      const CollocationTrajectory& s = *guess.solution;
      const double ts = std::min(s.t_begin() + tau * (s.t_end() - s.t_begin()), s.t_end());
      x = s.state_at(ts);
      u = s.control_at(ts);
    } else if (guess.control) {
      u = control(t);
      if (guess.rollout) {
        // Classical RK4 from the previous point, 8 steps.
        const int steps = 8;
        const double dt = (t - t_prev) / steps;
        x = x_prev;
        for (int s = 0; s < steps && j > 0; ++s) {
          const double ts = t_prev + s * dt;
          const Eigen::VectorXd u0 = control(ts), um = control(ts + 0.5 * dt), u1 = control(ts + dt);
          const Vector6d k1 = dyn.eval(x, u0);
          const Vector6d k2 = dyn.eval(x + 0.5 * dt * k1, um);
          const Vector6d k3 = dyn.eval(x + 0.5 * dt * k2, um);
          const Vector6d k4 = dyn.eval(x + dt * k3, u1);
          x += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
      } else {
        x = p.x_initial + tau * (p.x_final - p.x_initial);
      }
    } else {
      x = p.x_initial + tau * (p.x_final - p.x_initial);
      u = Eigen::VectorXd::Zero(nu);
    }
    x_prev = x;
    t_prev = t;
    if (j > 0 && j < P - 1) x = x.cwiseMax(p.x_min).cwiseMin(p.x_max);
    const int off = nlp.point_offset(j);
    w.segment<nx>(off) = x;
    w.segment(off + nx, nu) = u.cwiseMax(p.u_min).cwiseMin(p.u_max);
  }
  for (int k = 0; k < nlp.num_mid_controls(); ++k) {
    const double tau = nlp.mid_fraction(k);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(nu);
    if (guess.solution) {
      const CollocationTrajectory& s = *guess.solution;
      u = s.control_at(std::min(s.t_begin() + tau * (s.t_end() - s.t_begin()), s.t_end()));
    } else if (guess.control) {
      u = control(tau * T);
    }
    w.segment(nlp.mid_control_offset(k), nu) = u.cwiseMax(p.u_min).cwiseMin(p.u_max);
  }
  w.segment<nx>(nlp.point_offset(0)) = p.x_initial;
  w.segment<nx>(nlp.point_offset(P - 1)) = p.x_final;
  if (p.free_time) w(nlp.time_index()) = T;
  return w;
}

}  // namespace freeflex
