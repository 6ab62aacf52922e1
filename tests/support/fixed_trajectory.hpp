#pragma once
// A rigid trajectory that stays at one state: a linearization point for the first-order model.
#include <random>
#include <vector>

#include "freeflex/dynamics/zero_order.hpp"

namespace freeflex_test {

/// A fixed rigid state returned at every instant.
class FixedTrajectory : public freeflex::RigidTrajectory {
 public:
  explicit FixedTrajectory(freeflex::RigidState s) : s_(s) {}
  freeflex::RigidState at(const freeflex::Instant&) const override { return s_; }
  double t_begin() const override { return 0.0; }
  double t_end() const override { return 1.0; }
  std::vector<double> breakpoints() const override { return {}; }

 private:
  freeflex::RigidState s_;
};

/// A rigid state drawn from U(-1, 1): positions, rates and accelerations, the angle's
/// three components scaled by 3, 4 and 5 (the draws in a fixed order).
inline freeflex::RigidState random_rigid_state(std::mt19937& rng, std::uniform_real_distribution<double>& U) {
  freeflex::RigidState s;
  s.pos = Eigen::Vector3d(U(rng), U(rng), 3.0 * U(rng));
  s.vel = Eigen::Vector3d(U(rng), U(rng), 4.0 * U(rng));
  s.acc = Eigen::Vector3d(U(rng), U(rng), 5.0 * U(rng));
  return s;
}

}  // namespace freeflex_test
