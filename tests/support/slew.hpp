#pragma once
// Test fixture: the two-thruster slew of the maneuver tests and benchmarks.
#include <cmath>

#include <Eigen/Dense>

#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/trajopt/problem.hpp"

namespace freeflex_test {

/// The paper beam (1 m, 1 kg, EI 1) with two thrusters fixed to the body pushing along
/// body y at the tips s = 0 and s = L.
inline freeflex::FlexibleBody thruster_body(int noa = 2) {
  using T = freeflex::ForceElement::Type;
  return freeflex::FlexibleBody(freeflex::Beam(freeflex::BeamProperties::uniform(1.0, 1.0, 1.0)), noa,
                                {{"left", T::Thruster, 0.0, {0.0, 1.0}, false},
                                 {"right", T::Thruster, 1.0, {0.0, 1.0}, false}});
}

/// From rest at the origin to rest at (1 m, 0.5 m, 90°) in 3 s, |u| <= 1 N, minimum energy.
inline freeflex::ManeuverProblem slew() {
  freeflex::ManeuverProblem p;
  p.actuators = {0, 1};
  p.u_min = Eigen::Vector2d(-1.0, -1.0);
  p.u_max = Eigen::Vector2d(1.0, 1.0);
  p.x_final << 1.0, 0.5, 0.5 * std::acos(-1.0), 0.0, 0.0, 0.0;
  p.duration_s = 3.0;
  return p;
}

}  // namespace freeflex_test
