#pragma once
// A rigid trajectory that stays at one state: a linearization point for the first-order model.
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

}  // namespace freeflex_test
