#pragma once
// Test fixture: the paper's moment example (support/bodies.hpp) simulated over 3 s by the
// perturbation method, its first-order model about the nominal motion with the feedback
// actuators (the torque at o and both tip thrusters), and the control tests' weights
// Q = vibration_weight(1, 10, 1), R = diag(1, 1/4, 1/4).
#include <memory>
#include <vector>

#include "freeflex/control/lqr.hpp"
#include "freeflex/dynamics/first_order.hpp"
#include "freeflex/sim/simulate.hpp"
#include "support/bodies.hpp"

namespace freeflex_test {

struct MomentCase {
  freeflex::FlexibleBody body;
  freeflex::Excitation loads = moment_loads();
  freeflex::PerturbationResult pert;
  std::unique_ptr<freeflex::FirstOrderModel> model;
  Eigen::MatrixXd Q, R;
  explicit MomentCase(int noa) : body(moment_body(noa)) {
    using namespace freeflex;
    SimulationOptions so;
    so.duration_s = 3.0;
    so.output_step_s = 0.01;
    pert = simulate_perturbation(body, loads, so);
    const std::vector<int> inputs{1, 2, 3};
    model = std::make_unique<FirstOrderModel>(body, *pert.nominal, nominal_element_commands(loads, inputs), inputs);
    Q = vibration_weight(body, 1.0, 10.0, 1.0);
    R = Eigen::Vector3d(1.0, 0.25, 0.25).asDiagonal();
  }
};

}  // namespace freeflex_test
