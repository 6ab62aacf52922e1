#pragma once
// Shared by the benchmarks: the process CPU time, and the TV-LQR case (bench_control,
// tvlqr_accuracy): the paper's moment example
// (M_z = ±1 N m pulse at the centre of the 1 m, 1 kg, EI = 1 beam, 0-0.5 s +1, 0.5-1 s
// -1), its first-order model about the nominal motion over 3 s with feedback by a torque at
// o and body-y thrusters at both tips, Q = vibration_weight(1, 10, 1), R = diag(1, 1/4, 1/4).
#include <time.h>

#include <memory>
#include <optional>
#include <vector>

#include "freeflex/control/closed_loop.hpp"
#include "freeflex/control/tvlqr.hpp"
#include "freeflex/sim/simulate.hpp"

namespace freeflex_bench {

/// CPU time of the process [s].
inline double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

struct TvlqrCase {
  freeflex::FlexibleBody body;
  freeflex::Excitation loads;
  std::shared_ptr<const freeflex::RigidTrajectory> nominal;
  std::unique_ptr<freeflex::FirstOrderModel> model;
  Eigen::MatrixXd Q, R;
};

inline std::unique_ptr<TvlqrCase> moment_case(int noa) {
  using namespace freeflex;
  const Beam beam(BeamProperties::uniform(1.0, 1.0, 1.0));
  auto c = std::make_unique<TvlqrCase>(TvlqrCase{
      FlexibleBody(beam, noa,
                   {{"Mz", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false},
                    {"tau", ForceElement::Type::Torque, 0.5, {0.0, 0.0}, false},
                    {"left", ForceElement::Type::Thruster, 0.0, {0.0, 1.0}, false},
                    {"right", ForceElement::Type::Thruster, 1.0, {0.0, 1.0}, false}}),
      Excitation{{TimeProfile(TimeProfile::Kind::Steps, {0.0, 0.5, 1.0}, {1.0, -1.0}), std::nullopt, std::nullopt,
                  std::nullopt}},
      nullptr, nullptr, Eigen::MatrixXd(), Eigen::MatrixXd()});
  SimulationOptions so;
  so.duration_s = 3.0;
  so.output_step_s = 0.01;
  c->nominal = simulate_perturbation(c->body, c->loads, so).nominal;
  const std::vector<int> inputs{1, 2, 3};
  c->model = std::make_unique<FirstOrderModel>(c->body, *c->nominal, nominal_element_commands(c->loads, inputs), inputs);
  c->Q = vibration_weight(c->body, 1.0, 10.0, 1.0);
  c->R = Eigen::Vector3d(1.0, 0.25, 0.25).asDiagonal();
  return c;
}

}  // namespace freeflex_bench
