#pragma once
// Numbers in messages: one formatting for every layer's error and status text.
#include <sstream>
#include <string>

namespace freeflex::util {

/// `v` with `digits` significant digits, as an ostream prints it (1e-08, 0.25, 3).
inline std::string format_number(double v, int digits = 10) {
  std::ostringstream os;
  os.precision(digits);
  os << v;
  return os.str();
}

}  // namespace freeflex::util
