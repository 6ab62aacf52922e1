#pragma once
// Test fixtures: beams that exercise every term of the models.
#include <vector>

#include "freeflex/dynamics/flexible_body.hpp"

namespace freeflex_test {

/// o off the mass centre (S_o != 0), a hub, a tip mass and two segments.
inline freeflex::BeamProperties rich_beam() {
  freeflex::BeamProperties p;
  p.segments = {{0.6, 1.2, 2.0}, {0.5, 0.7, 1.5}};
  p.reference_m = 0.45;
  p.hub_mass_kg = 0.3;
  p.hub_rotary_inertia_kgm2 = 0.02;
  p.point_masses = {{1.1, 0.25}};
  return p;
}

/// An inertial force, a follower thruster, a body thruster and a torque, in that order.
inline std::vector<freeflex::ForceElement> rich_elements() {
  using T = freeflex::ForceElement::Type;
  return {{"force", T::Force, 0.9, {0.3, -0.8}, false},
          {"follower", T::Thruster, 1.1, {0.2, 1.0}, true},
          {"thruster", T::Thruster, 0.1, {-0.5, 0.4}, false},
          {"torque", T::Torque, 0.7, {0.0, 0.0}, false}};
}

}  // namespace freeflex_test
