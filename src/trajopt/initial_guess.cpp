// Starting points for the collocation NLP (trajopt/collocation.hpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "freeflex/trajopt/collocation.hpp"

namespace freeflex {

namespace {


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
  const ManeuverDynamics& dyn = nlp.dynamics();
  const int nu = dyn.nu(), P = nlp.num_points(), nx = dyn.nx();
  constexpr int n0 = RigidDynamics::nx;
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
  // The straight line for the rigid part; the elastic part (if any) at rest.
  auto line = [&](double tau) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(nx);
    x.head<n0>() = p.x_initial + tau * (p.x_final - p.x_initial);
    return x;
  };
  Eigen::VectorXd x_prev = line(0.0);
  double t_prev = 0.0;
  for (int j = 0; j < P; ++j) {
    const double tau = nlp.point_fraction(j), t = tau * T;
    Eigen::VectorXd x;
    Eigen::VectorXd u;
    if (guess.solution) {
      const CollocationTrajectory& s = *guess.solution;
      const double ts = std::min(s.t_begin() + tau * (s.t_end() - s.t_begin()), s.t_end());
      // A solution with the same state keeps its elastic part; a rigid one starts it at rest.
      const Eigen::VectorXd xs = s.full_state_at(Instant::at(ts));
      x = Eigen::VectorXd::Zero(nx);
      if (xs.size() == nx)
        x = xs;
      else
        x.head<n0>() = xs.head<n0>();
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
          const Eigen::VectorXd k1 = dyn.eval(x, u0);
          const Eigen::VectorXd k2 = dyn.eval(x + 0.5 * dt * k1, um);
          const Eigen::VectorXd k3 = dyn.eval(x + 0.5 * dt * k2, um);
          const Eigen::VectorXd k4 = dyn.eval(x + dt * k3, u1);
          x += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
      } else {
        x = line(tau);
      }
    } else {
      x = line(tau);
      u = Eigen::VectorXd::Zero(nu);
    }
    x_prev = x;
    t_prev = t;
    if (j > 0 && j < P - 1) x.head<n0>() = x.head<n0>().cwiseMax(p.x_min).cwiseMin(p.x_max);
    const int off = nlp.point_offset(j);
    w.segment(off, nx) = x;
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
  w.segment<n0>(nlp.point_offset(0)) = p.x_initial;
  w.segment(nlp.point_offset(0) + n0, nx - n0).setZero();
  w.segment<n0>(nlp.point_offset(P - 1)) = p.x_final;
  if (p.free_time) w(nlp.time_index()) = T;
  return w;
}

}  // namespace freeflex
