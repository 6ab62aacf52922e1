#pragma once
// Test fixtures: beams that exercise every term of the models.
#include <optional>
#include <utility>
#include <vector>

#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/dynamics/flexible_body.hpp"
#include "freeflex/dynamics/zero_order.hpp"
#include "freeflex/model/loads.hpp"

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

/// The paper's moment example (1 m, 1 kg, EI = 1): the load M_z = ±1 N m at the centre
/// (0–0.5 s +1, 0.5–1 s −1, moment_loads()) drives the nominal maneuver θ0: 0 → 3 rad.
/// Feedback actuators: a torque at o (element 1) and body-y thrusters at both tips (2, 3).
inline freeflex::FlexibleBody moment_body(int noa, std::vector<double> damping_ratios = {}) {
  using T = freeflex::ForceElement::Type;
  const freeflex::Beam beam(freeflex::BeamProperties::uniform(1.0, 1.0, 1.0));
  return freeflex::FlexibleBody(beam, noa,
                                {{"Mz", T::Torque, 0.5, {0.0, 0.0}, false},
                                 {"tau", T::Torque, 0.5, {0.0, 0.0}, false},
                                 {"left", T::Thruster, 0.0, {0.0, 1.0}, false},
                                 {"right", T::Thruster, 1.0, {0.0, 1.0}, false}},
                                std::move(damping_ratios));
}

inline freeflex::Excitation moment_loads() {
  using freeflex::TimeProfile;
  return freeflex::Excitation{
      {TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0}), std::nullopt, std::nullopt, std::nullopt}};
}

/// The paper beam (1 m, 1 kg, EI 1, o at the centre) with a torque at o and body-y
/// thrusters at both tips: the actuators of the control tests.
inline freeflex::FlexibleBody actuated_beam(int noa) {
  using T = freeflex::ForceElement::Type;
  const freeflex::Beam beam(freeflex::BeamProperties::uniform(1.0, 1.0, 1.0));
  return freeflex::FlexibleBody(beam, noa,
                                {{"tau", T::Torque, 0.5, {0.0, 0.0}, false},
                                 {"left", T::Thruster, 0.0, {0.0, 1.0}, false},
                                 {"right", T::Thruster, 1.0, {0.0, 1.0}, false}});
}

/// The beam held at rest at a fixed attitude: a time-invariant first-order model.
class RestTrajectory : public freeflex::RigidTrajectory {
 public:
  explicit RestTrajectory(double theta) { s_.pos(2) = theta; }
  freeflex::RigidState at(const freeflex::Instant&) const override { return s_; }
  double t_begin() const override { return 0.0; }
  double t_end() const override { return 0.0; }
  std::vector<double> breakpoints() const override { return {}; }

 private:
  freeflex::RigidState s_;
};

inline freeflex::CommandFunction no_commands() {
  return [](const freeflex::Instant&, Eigen::Ref<Eigen::VectorXd> c) { c.setZero(); };
}

}  // namespace freeflex_test
