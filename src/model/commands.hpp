#pragma once
// Every element's command at an instant, written into a buffer the caller keeps: the
// allocation-free form of Excitation::commands for the right-hand sides that call it
// tens of thousands of times. Private to src/.
#include <Eigen/Dense>

#include "freeflex/model/loads.hpp"

namespace freeflex::detail {

/// commands(e) for every element of `ex`; `commands` has ex.profiles.size() entries.
void evaluate_commands(const Excitation& ex, const Instant& at, Eigen::Ref<Eigen::VectorXd> commands);

}  // namespace freeflex::detail
