#include "design_reader.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace freeflex::io_detail {
namespace {

std::string show(const toml::node& n) {
  std::ostringstream os;
  if (n.is_string()) os << '"' << *n.value<std::string>() << '"';  // as the user typed it
  else n.visit([&](auto&& v) { os << v; });
  std::string s = os.str();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

void Problems::add(int line, const std::string& message) {
  std::ostringstream os;
  os << "design '" << source_ << "'";
  if (line > 0) os << " line " << line;
  os << ": " << message;
  // keep problems in file order, whatever order the sections were read in
  auto at = list_.end();
  while (at != list_.begin() && lines_[at - list_.begin() - 1] > line) --at;
  lines_.insert(lines_.begin() + (at - list_.begin()), line);
  list_.insert(at, os.str());
}

bool Range::contains(double v) const {
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

std::string Range::describe() const {
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi)
    return std::string("must be in ") + (lo_open ? "(" : "[") + fmt(lo) + ", " + fmt(hi) + (hi_open ? ")" : "]");
  if (has_lo) return std::string("must be ") + (lo_open ? "> " : ">= ") + fmt(lo);
  if (has_hi) return std::string("must be ") + (hi_open ? "< " : "<= ") + fmt(hi);
  return "must be a finite number";
}

Section::Section(const toml::table* table, std::string path, Problems& problems, int line)
    : table_(table), path_(std::move(path)), problems_(problems), line_(line) {}

std::string Section::key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

int Section::line_of(const toml::node& n) const {
  const int l = static_cast<int>(n.source().begin.line);
  return l > 0 ? l : line_;
}

bool Section::has(const std::string& key) const { return table_ && table_->get(key) != nullptr; }

const toml::node* Section::get(const std::string& key) {
  asked_.insert(key);
  return table_ ? table_->get(key) : nullptr;
}

void Section::problem(const std::string& key, const std::string& message) {
  const toml::node* n = table_ ? table_->get(key) : nullptr;
  problems_.add(n ? line_of(*n) : line_, message);
}

std::optional<double> Section::number(const std::string& key, const Range& range, bool required) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) problems_.add(line_, key_path(key) + " is required (a number that " + range.describe() + ")");
    return std::nullopt;
  }
  if (!n->is_number()) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", must be a number");
    return std::nullopt;
  }
  const double v = *n->value<double>();
  if (!std::isfinite(v)) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", must be a finite number");
    return std::nullopt;
  }
  if (!range.contains(v)) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", " + range.describe());
    return std::nullopt;
  }
  return v;
}

std::optional<long long> Section::integer(const std::string& key, long long lo, long long hi, bool required) {
  const std::string allowed = "must be a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  const toml::node* n = get(key);
  if (!n) {
    if (required) problems_.add(line_, key_path(key) + " is required (" + allowed.substr(5) + ")");
    return std::nullopt;
  }
  if (!n->is_integer()) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", " + allowed);
    return std::nullopt;
  }
  const long long v = *n->value<long long>();
  if (v < lo || v > hi) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", " + allowed);
    return std::nullopt;
  }
  return v;
}

std::optional<bool> Section::boolean(const std::string& key, bool required) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) problems_.add(line_, key_path(key) + " is required (true or false)");
    return std::nullopt;
  }
  if (!n->is_boolean()) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", must be true or false");
    return std::nullopt;
  }
  return *n->value<bool>();
}

std::optional<std::string> Section::string(const std::string& key, bool required, bool identifier) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) problems_.add(line_, key_path(key) + " is required (a string)");
    return std::nullopt;
  }
  if (!n->is_string()) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", must be a string");
    return std::nullopt;
  }
  std::string v = *n->value<std::string>();
  if (identifier) {
    bool ok = !v.empty() && v.size() <= 64;
    for (char c : v) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-');
    if (!ok) {
      problems_.add(line_of(*n), key_path(key) + " = " + show(*n) +
                                     ", must be 1 to 64 letters, digits, '_' or '-' (it names files)");
      return std::nullopt;
    }
  }
  return v;
}

std::optional<std::string> Section::choice(const std::string& key, const std::vector<std::string>& allowed,
                                           bool required) {
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "'" : ", '") + a + "'";
  const toml::node* n = table_ ? table_->get(key) : nullptr;
  if (!n && required) {
    asked_.insert(key);
    problems_.add(line_, key_path(key) + " is required (one of " + list + ")");
    return std::nullopt;
  }
  auto v = string(key, false);
  if (!v) return std::nullopt;
  for (const auto& a : allowed)
    if (*v == a) return v;
  problems_.add(line_of(*n), key_path(key) + " = \"" + *v + "\", must be one of " + list);
  return std::nullopt;
}

std::optional<std::vector<long long>> Section::integer_array(const std::string& key, long long lo, long long hi,
                                                             bool required) {
  const std::string allowed = "must be an array of whole numbers in [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "]";
  const toml::node* n = get(key);
  if (!n) {
    if (required) problems_.add(line_, key_path(key) + " is required (" + allowed.substr(5) + ")");
    return std::nullopt;
  }
  const toml::array* arr = n->as_array();
  if (!arr || arr->empty()) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", " + allowed + " (not empty)");
    return std::nullopt;
  }
  std::vector<long long> out;
  for (const auto& e : *arr) {
    if (!e.is_integer() || *e.value<long long>() < lo || *e.value<long long>() > hi) {
      problems_.add(line_of(*n), key_path(key) + " contains " + show(e) + ", " + allowed);
      return std::nullopt;
    }
    out.push_back(*e.value<long long>());
  }
  return out;
}

std::optional<std::vector<double>> Section::number_array(const std::string& key, const Range& range,
                                                         bool required) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) problems_.add(line_, key_path(key) + " is required (an array of numbers)");
    return std::nullopt;
  }
  const toml::array* arr = n->as_array();
  if (!arr || arr->empty()) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", must be a non-empty array of numbers");
    return std::nullopt;
  }
  std::vector<double> out;
  for (const auto& e : *arr) {
    const bool ok = e.is_number() && std::isfinite(*e.value<double>()) && range.contains(*e.value<double>());
    if (!ok) {
      problems_.add(line_of(*n), key_path(key) + " contains " + show(e) + ", each entry " + range.describe());
      return std::nullopt;
    }
    out.push_back(*e.value<double>());
  }
  return out;
}

std::optional<std::vector<std::string>> Section::string_array(const std::string& key, bool required) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) problems_.add(line_, key_path(key) + " is required (an array of strings)");
    return std::nullopt;
  }
  const toml::array* arr = n->as_array();
  if (!arr || arr->empty()) {
    problems_.add(line_of(*n), key_path(key) + " = " + show(*n) + ", must be a non-empty array of strings");
    return std::nullopt;
  }
  std::vector<std::string> out;
  for (const auto& e : *arr) {
    if (!e.is_string()) {
      problems_.add(line_of(*n), key_path(key) + " contains " + show(e) + ", each entry must be a string");
      return std::nullopt;
    }
    out.push_back(*e.value<std::string>());
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> Section::raw_entries() {
  std::vector<std::pair<std::string, std::string>> out;
  if (!table_) return out;
  for (const auto& [k, v] : *table_) {
    const std::string key(k.str());
    asked_.insert(key);
    if (v.is_string()) {
      out.emplace_back(key, *v.value<std::string>());
    } else if (v.is_integer()) {
      out.emplace_back(key, std::to_string(*v.value<long long>()));
    } else if (v.is_floating_point()) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.17g", *v.value<double>());
      out.emplace_back(key, buf);
    } else if (v.is_boolean()) {
      out.emplace_back(key, *v.value<bool>() ? "yes" : "no");
    } else {
      problems_.add(line_of(v), key_path(key) + " must be a string, number or boolean (it is passed to the solver)");
    }
  }
  return out;
}

Section Section::table(const std::string& key) {
  const toml::node* n = get(key);
  if (!n) return Section(nullptr, key_path(key), problems_, line_);
  if (!n->is_table()) {
    problems_.add(line_of(*n), key_path(key) + " must be a table ([" + key_path(key) + "])");
    return Section(nullptr, key_path(key), problems_, line_of(*n));
  }
  return Section(n->as_table(), key_path(key), problems_, line_of(*n));
}

std::vector<Section> Section::table_array(const std::string& key) {
  std::vector<Section> out;
  const toml::node* n = get(key);
  if (!n) return out;
  const toml::array* arr = n->as_array();
  if (!arr || !arr->is_array_of_tables()) {
    problems_.add(line_of(*n), key_path(key) + " must be an array of tables ([[" + key_path(key) + "]])");
    return out;
  }
  int i = 0;
  for (const auto& e : *arr) {
    ++i;
    out.emplace_back(e.as_table(), key_path(key) + "[" + std::to_string(i) + "]", problems_, line_of(e));
  }
  return out;
}

void Section::finish() {
  if (!table_) return;
  std::string allowed;
  for (const auto& k : asked_) allowed += (allowed.empty() ? "" : ", ") + k;
  for (const auto& [k, v] : *table_) {
    const std::string key(k.str());
    if (asked_.count(key)) continue;
    problems_.add(line_of(v), "unknown key '" + key_path(key) + "' (allowed here: " + allowed + ")");
  }
}

}  // namespace freeflex::io_detail
