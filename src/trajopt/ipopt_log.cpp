// Reading Ipopt's log: the verdict of its derivative checker.
#include <cstdlib>
#include <string>

#include "trajopt/ipopt_adapter.hpp"

namespace freeflex::detail {

int derivative_errors(const std::string& log) {
  int total = -1;
  std::size_t pos = 0;
  const std::string ok = "No errors detected by derivative checker.";
  const std::string bad = "Derivative checker detected ";
  while (true) {
    const std::size_t a = log.find(ok, pos), b = log.find(bad, pos);
    if (a == std::string::npos && b == std::string::npos) break;
    if (total < 0) total = 0;
    if (b == std::string::npos || (a != std::string::npos && a < b)) {
      pos = a + ok.size();
    } else {
      total += std::atoi(log.c_str() + b + bad.size());
      pos = b + bad.size();
    }
  }
  return total;
}

}  // namespace freeflex::detail
