// Ipopt options checked against Ipopt's own registry (trajopt/ipopt_options.hpp): the
// registry of an IpoptApplication lists every option with its type, bounds, default and
// valid strings.
#include "trajopt/ipopt_options.hpp"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include <coin/IpIpoptApplication.hpp>
#include <coin/IpRegOptions.hpp>

namespace freeflex::detail {
namespace {

/// The registry, made once: an IpoptApplication registers every option on construction.
Ipopt::RegisteredOptions& registry() {
  static const Ipopt::SmartPtr<Ipopt::IpoptApplication> app = new Ipopt::IpoptApplication(false);
  return *app->RegOptions();
}

std::string number_text(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

/// Edit distance, for "did you mean".
std::size_t distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string suggestion(const std::string& name) {
  std::string best;
  std::size_t best_d = 4;  // at most 3 edits away
  for (const auto& [candidate, option] : registry().RegisteredOptionsList()) {
    const std::size_t d = distance(name, candidate);
    if (d < best_d) {
      best_d = d;
      best = candidate;
    }
  }
  return best.empty() ? "" : " (did you mean '" + best + "'?)";
}

/// "must be a number > 0", "must be a whole number in [0, 12]": the option's bounds.
std::string allowed(const Ipopt::RegisteredOption& o, bool integer) {
  const auto lo = [&] { return integer ? std::to_string(o.LowerInteger()) : number_text(o.LowerNumber()); };
  const auto hi = [&] { return integer ? std::to_string(o.UpperInteger()) : number_text(o.UpperNumber()); };
  const bool lo_strict = !integer && o.LowerStrict(), hi_strict = !integer && o.UpperStrict();
  std::string s = integer ? "must be a whole number" : "must be a number";
  if (o.HasLower() && o.HasUpper())
    return s + " in " + (lo_strict ? "(" : "[") + lo() + ", " + hi() + (hi_strict ? ")" : "]");
  if (o.HasLower()) return s + (lo_strict ? " > " : " >= ") + lo();
  if (o.HasUpper()) return s + (hi_strict ? " < " : " <= ") + hi();
  return s;
}

std::string valid_strings(const Ipopt::RegisteredOption& o) {
  std::string list;
  for (const auto& e : o.GetValidStrings()) list += (list.empty() ? "'" : ", '") + e.value_ + "'";
  return list;
}

}  // namespace

std::string ipopt_option_problem(const std::string& name, const std::string& value, OptionText kind) {
  const Ipopt::SmartPtr<const Ipopt::RegisteredOption> reg = registry().GetOption(name);
  if (Ipopt::IsNull(reg)) return "is not an Ipopt option" + suggestion(name);
  const Ipopt::RegisteredOption& o = *reg;
  const std::string whose = " (Ipopt's " + name + ")";
  switch (o.Type()) {
    case Ipopt::OT_Integer: {
      if (kind != OptionText::Integer) return allowed(o, true) + whose;
      errno = 0;
      const long long v = std::strtoll(value.c_str(), nullptr, 10);
      if (errno == ERANGE || v < INT_MIN || v > INT_MAX || !o.IsValidIntegerSetting(static_cast<Ipopt::Index>(v)))
        return allowed(o, true) + whose;
      return "";
    }
    case Ipopt::OT_Number: {
      if (kind != OptionText::Integer && kind != OptionText::Number) return allowed(o, false) + whose;
      const double v = std::strtod(value.c_str(), nullptr);
      if (!std::isfinite(v) || !o.IsValidNumberSetting(v)) return allowed(o, false) + whose;
      return "";
    }
    case Ipopt::OT_String: {
      const std::string list = valid_strings(o);
      const bool any = list == "'*'";  // Ipopt's mark for free text (file names)
      if (kind != OptionText::String && kind != OptionText::Boolean)
        return "must be a string" + (any ? std::string() : ", one of " + list) + whose;
      if (!o.IsValidStringSetting(value)) return "must be one of " + list + whose;
      return "";
    }
    default:
      return "has a type this check does not know" + whose;
  }
}

}  // namespace freeflex::detail
