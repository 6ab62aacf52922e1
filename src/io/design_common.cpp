// What the section readers of a design file share (io/design_sections.hpp): count bounds,
// actuator lookup, and the library's validation mapped back to the file's keys.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <regex>

#include "io/design_sections.hpp"

namespace freeflex::io_detail {
namespace {

/// Rows (or samples, grid points) that `span` gives at `step`, as the simulators count
/// them: ceil(span / step) steps plus the end point.
double count_of(double span, double step) { return std::ceil(span / step - 1e-9) + 1.0; }

}  // namespace

std::string show_count(double n) {
  if (n < 1e15) return std::to_string(static_cast<long long>(n));
  return shortest(n);
}

bool check_count(Section& s, const std::string& key, const std::string& lead, const std::string& other, double span,
                 double step, const std::string& what, double limit, const std::string& advice) {
  const double n = count_of(span, step);
  if (n <= limit) return true;
  s.problem(key, lead + " with " + other + " gives " + show_count(n) + " " + what + "; at most " + show_count(limit) +
                     ": " + advice);
  return false;
}

std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

std::string lower_trimmed(const std::string& s) {
  std::string t = trimmed(s);
  for (char& ch : t) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return t;
}

double beam_length(const Design& d) {
  double L = 0.0;
  for (const auto& s : d.beam.segments) L += s.length_m;
  return L;
}

double loads_end(const Design& d) {
  double end = 0.0;
  for (const auto& l : d.loads) end = std::max(end, l.profile.times().back());
  return end;
}

std::vector<int> actuator_indices(Section& s, const std::string& key, const std::vector<std::string>& names,
                                  const Design& d, const std::vector<std::string>& rejected) {
  std::vector<int> idx;
  for (std::size_t k = 0; k < names.size(); ++k) {
    const std::string& name = names[k];
    const auto first = std::find(names.begin(), names.end(), name) - names.begin();
    if (first < static_cast<std::ptrdiff_t>(k)) {
      if (std::find(names.begin() + first + 1, names.end(), name) - names.begin() == static_cast<std::ptrdiff_t>(k))
        s.problem(key, s.key_path(key) + " lists \"" + name + "\" more than once; each actuator at most once");
      continue;
    }
    int found = -1;
    for (std::size_t i = 0; i < d.actuators.size(); ++i)
      if (d.actuators[i].element.name == name) found = static_cast<int>(i);
    if (found < 0 && std::find(rejected.begin(), rejected.end(), name) != rejected.end()) continue;
    if (found < 0) {
      std::string known;
      for (const auto& a : d.actuators) known += (known.empty() ? "'" : ", '") + a.element.name + "'";
      s.problem(key, s.key_path(key) + ": \"" + name + "\" is not an [[actuator]] (known: " +
                         (known.empty() ? "none" : known) + ")");
      continue;
    }
    idx.push_back(static_cast<int>(d.loads.size()) + found);
  }
  return idx;
}

void report_field_problems(Section& s, const std::vector<FieldProblem>& problems, const FieldKeys& keys) {
  auto key_of = [&keys](const std::string& field) -> const std::string* {
    const std::string base = field.substr(0, field.find('['));  // "energy_weights[1]" -> "energy_weights"
    for (const auto& [f, k] : keys)
      if (f == base) return &k;
    return nullptr;
  };
  for (const FieldProblem& p : problems) {
    const std::string* key = key_of(p.field);
    if (!key || s.has_problem(*key)) continue;
    std::string message = p.message;
    for (const auto& [f, k] : keys) {  // whole words only: "t_min_s", not the end of "dt_min_s"
      const std::string word = std::regex_replace(f, std::regex("\\."), "\\.");
      message = std::regex_replace(message, std::regex("\\b" + word + "\\b"), k);
    }
    const bool leads = message.rfind(*key, 0) == 0;
    s.problem(*key, leads ? s.path() + "." + message : s.path() + ": " + message);
  }
}

}  // namespace freeflex::io_detail
