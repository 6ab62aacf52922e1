#pragma once
// Ipopt's own option registry, asked about options before any work: what the design's
// [maneuver.ipopt] table may set, of which type, within which bounds, with which string
// values. Ipopt's headers stay in trajopt/ipopt_options.cpp. Private to src/.
#include <string>

namespace freeflex::detail {

/// How a value was written (TOML's type), to be held against the option's type.
enum class OptionText { String, Integer, Number, Boolean };

/// What is wrong with setting Ipopt option `name` to `value` (written as `kind`; booleans
/// as "yes" / "no") by Ipopt's registry: "" when Ipopt accepts it, else what is allowed
/// ("is not an Ipopt option (did you mean 'max_iter'?)", "must be a whole number >= 0
/// (Ipopt's max_iter)", "must be one of 'none', 'first-order', ...").
std::string ipopt_option_problem(const std::string& name, const std::string& value, OptionText kind);

}  // namespace freeflex::detail
