#pragma once
// Problems found by the validation of a problem or options struct, field by field: what
// every validate() throws, and what design files map back to their keys.
#include <stdexcept>
#include <string>
#include <vector>

namespace freeflex {

/// One problem with one field: `field` names it as the struct spells it ("t_min_s",
/// "u_min[1]", "integrator.rtol"), `message` starts with that name and quotes the values
/// ("t_min_s = 5 > t_max_s = 2, expected t_min_s <= t_max_s").
struct FieldProblem {
  std::string field;
  std::string message;
};

/// Throws std::invalid_argument "<what>: <message>; <message>; ..." when `problems` is
/// not empty.
inline void throw_if_any(const std::string& what, const std::vector<FieldProblem>& problems) {
  if (problems.empty()) return;
  std::string msg = what + ": ";
  for (std::size_t i = 0; i < problems.size(); ++i) msg += (i ? "; " : "") + problems[i].message;
  throw std::invalid_argument(msg);
}

}  // namespace freeflex
