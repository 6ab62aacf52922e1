// freeflex's version and the versions of the numerical libraries it links.
#include "freeflex/version.hpp"

#include <coin/IpoptConfig.h>
#include <nlopt.hpp>
#include <sundials/sundials_config.h>
#include <toml++/toml.h>

#include <Eigen/Core>
#include <sstream>

namespace freeflex {

std::string version() { return FREEFLEX_VERSION; }

std::string dependency_versions() {
  std::ostringstream os;
  int major = 0, minor = 0, bugfix = 0;
  nlopt::version(major, minor, bugfix);  // asks the linked library, not the header
  os << "Eigen " << EIGEN_WORLD_VERSION << '.' << EIGEN_MAJOR_VERSION << '.' << EIGEN_MINOR_VERSION
     << ", Ipopt " << IPOPT_VERSION << ", SUNDIALS " << SUNDIALS_VERSION << ", NLopt " << major << '.'
     << minor << '.' << bugfix << ", toml++ " << TOML_LIB_MAJOR << '.' << TOML_LIB_MINOR << '.'
     << TOML_LIB_PATCH;
  return os.str();
}

}  // namespace freeflex
