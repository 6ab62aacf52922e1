#pragma once
// freeflex's version and the numerical libraries linked in.
#include <string>

namespace freeflex {

/// freeflex's version, e.g. "0.1.0".
std::string version();
/// One line naming the numerical libraries linked in (Eigen, Ipopt, SUNDIALS, NLopt, toml++).
std::string dependency_versions();

}  // namespace freeflex
