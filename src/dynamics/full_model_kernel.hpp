#pragma once
// The full model's right-hand side at run-time size (private to src/): what the kernels
// FullModel::rhs compiles for common sizes must equal, to the bit in a default build.
#include <Eigen/Dense>

#include "freeflex/dynamics/full_model.hpp"

namespace freeflex::detail {

/// FullModel::rhs (without geometric stiffening) through the kernel whose number of
/// elastic coordinates is a run-time value, whatever the body's size.
bool full_rhs_runtime_size(const FullModel& model, FullModel::Data& d, const Eigen::Ref<const Eigen::VectorXd>& x,
                           const Eigen::Ref<const Eigen::VectorXd>& commands);

}  // namespace freeflex::detail
