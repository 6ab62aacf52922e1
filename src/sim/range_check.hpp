#pragma once
// The check that ends a run whose elastic deflection has grown past the model's range
// (SimulationOptions::max_deflection_ratio). Private to src/sim.
#include <functional>
#include <string>

#include <Eigen/Dense>

#include "freeflex/sim/simulate.hpp"

namespace freeflex::detail {

/// A range check for OdeSystem: q is at x.segment(q_offset, n), or q = to_q η with η there.
std::function<std::string(const Instant&, const Eigen::Ref<const Eigen::VectorXd>&)> deflection_check(
    const FlexibleBody& body, const SimulationOptions& options, int q_offset, const Eigen::MatrixXd* to_q = nullptr);

/// For OdeSystem::last_error of a run of the full model: what its refusal of a state (the
/// mass matrix not positive definite) means. With geometric stiffening it gives the share
/// of the rotary inertia about o that the frame keeps by itself at rest, found once at
/// the first call, and says that the range shrinks as noa grows (docs/theory.md §14).
std::function<std::string()> mass_matrix_failure(const FlexibleBody& body);

}  // namespace freeflex::detail
