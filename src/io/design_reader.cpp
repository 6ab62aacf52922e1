// The validating reader over a design file's TOML tables (io/design_reader.hpp).
#include "io/design_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "util/format.hpp"

namespace freeflex::io_detail {

std::string shortest(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
  if (v == std::floor(v) && std::abs(v) < 1e6) return std::to_string(static_cast<long long>(v));  // 10000, not 1e+04
  for (int digits = 1; digits < 17; ++digits) {
    std::string s = util::format_number(v, digits);
    if (std::strtod(s.c_str(), nullptr) == v) return s;
  }
  return util::format_number(v, 17);
}

std::string show(const toml::node& n) {
  std::string s;
  if (n.is_string()) {
    s = '"' + *n.value<std::string>() + '"';  // as the user typed it
  } else if (n.is_floating_point()) {
    // shortest round-trip digits (-0.1, not -0.10000000000000001), still a TOML float
    const double v = *n.value<double>();
    s = shortest(v);
    if (std::isfinite(v) && s.find_first_of(".e") == std::string::npos) s += ".0";
  } else if (const toml::array* arr = n.as_array()) {
    s = "[";
    for (std::size_t i = 0; i < arr->size() && s.size() <= 60; ++i) s += (i ? ", " : "") + show(*arr->get(i));
    s += "]";
  } else {
    std::ostringstream os;
    n.visit([&](auto&& v) { os << v; });
    s = os.str();
  }
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

namespace {

std::string fmt(double v) { return shortest(v); }

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

bool Problems::troubled(const std::string& key_path) const {
  for (std::string p = key_path; !p.empty();) {
    if (troubled_.count(p)) return true;
    const auto cut = p.find_last_of(".[");
    p = cut == std::string::npos ? "" : p.substr(0, cut);
  }
  return false;
}

bool Range::contains(double v) const {
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return v >= sane_lo && v <= sane_hi;
}

namespace {

std::string allowed_text(const Range& r) {
  const bool has_lo = std::isfinite(r.lo), has_hi = std::isfinite(r.hi);
  if (has_lo && has_hi)
    return std::string("must be in ") + (r.lo_open ? "(" : "[") + fmt(r.lo) + ", " + fmt(r.hi) +
           (r.hi_open ? ")" : "]");
  if (has_lo) return std::string("must be ") + (r.lo_open ? "> " : ">= ") + fmt(r.lo);
  if (has_hi) return std::string("must be ") + (r.hi_open ? "< " : "<= ") + fmt(r.hi);
  return "must be a finite number";
}

std::string supported_text(const Range& r) {
  const bool has_lo = std::isfinite(r.sane_lo), has_hi = std::isfinite(r.sane_hi);
  if (has_lo && has_hi) return "within [" + fmt(r.sane_lo) + ", " + fmt(r.sane_hi) + "]";
  if (has_lo) return "at least " + fmt(r.sane_lo);
  if (has_hi) return "at most " + fmt(r.sane_hi);
  return "";
}

}  // namespace

std::string Range::describe() const {
  const std::string sup = supported_text(*this);
  return allowed_text(*this) + (sup.empty() ? "" : ", " + sup);
}

std::string Range::describe(double v) const {
  Range wide = *this;
  wide.sane_lo = -std::numeric_limits<double>::infinity();
  wide.sane_hi = std::numeric_limits<double>::infinity();
  if (!wide.contains(v)) return allowed_text(*this);
  return "must be " + supported_text(*this) + " (the supported range)";
}

Section::Section(const toml::table* table, std::string path, Problems& problems, int line)
    : table_(table), path_(std::move(path)), problems_(problems), line_(line) {}

std::string Section::key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

int Section::line_of(const toml::node& n) const {
  const int l = static_cast<int>(n.source().begin.line);
  return l > 0 ? l : line_;
}

bool Section::has(const std::string& key) const { return table_ && table_->get(key) != nullptr; }

int Section::line(const std::string& key) const {
  const toml::node* n = table_ ? table_->get(key) : nullptr;
  return n ? line_of(*n) : line_;
}

void Section::report(const std::string& key, int line, const std::string& message) {
  troubled_.insert(key);
  problems_.mark(key_path(key));
  problems_.add(line, message);
}

const toml::node* Section::get(const std::string& key) {
  asked_.insert(key);
  return table_ ? table_->get(key) : nullptr;
}

void Section::problem(const std::string& key, const std::string& message) {
  troubled_.insert(key);
  problems_.mark(key_path(key));
  const toml::node* n = table_ ? table_->get(key) : nullptr;
  problems_.add(n ? line_of(*n) : line_, message);
}

std::optional<double> Section::number(const std::string& key, const Range& range, bool required) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) report(key, line_, key_path(key) + " is required (a number that " + range.describe() + ")");
    return std::nullopt;
  }
  if (!n->is_number()) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", must be a number");
    return std::nullopt;
  }
  const double v = *n->value<double>();
  if (!std::isfinite(v)) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", must be a finite number");
    return std::nullopt;
  }
  if (!range.contains(v)) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", " + range.describe(v));
    return std::nullopt;
  }
  return v;
}

std::optional<long long> Section::integer(const std::string& key, long long lo, long long hi, bool required) {
  const std::string allowed = "must be a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  const toml::node* n = get(key);
  if (!n) {
    if (required) report(key, line_, key_path(key) + " is required (" + allowed.substr(5) + ")");
    return std::nullopt;
  }
  if (!n->is_integer()) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", " + allowed);
    return std::nullopt;
  }
  const long long v = *n->value<long long>();
  if (v < lo || v > hi) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", " + allowed);
    return std::nullopt;
  }
  return v;
}

std::optional<long long> Section::integer_or_word(const std::string& key, long long lo, long long hi,
                                                  const std::string& word, long long word_value, bool required) {
  const toml::node* n = get(key);
  if (n && n->is_string()) {
    if (*n->value<std::string>() == word) return word_value;
    report(key, line_of(*n),
           key_path(key) + " = " + show(*n) + ", must be a whole number in [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "] or \"" + word + "\"");
    return std::nullopt;
  }
  return integer(key, lo, hi, required);
}

std::optional<bool> Section::boolean(const std::string& key, bool required) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) report(key, line_, key_path(key) + " is required (true or false)");
    return std::nullopt;
  }
  if (!n->is_boolean()) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", must be true or false");
    return std::nullopt;
  }
  return *n->value<bool>();
}

bool plain_name(const std::string& v, const char* also) {
  if (v.empty() || v.size() > 64 || v.front() == '.') return false;
  for (char c : v)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && (c == '\0' || !std::strchr(also, c)))
      return false;
  return true;
}

std::optional<std::string> Section::string(const std::string& key, bool required, bool identifier) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) report(key, line_, key_path(key) + " is required (a string)");
    return std::nullopt;
  }
  if (!n->is_string()) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", must be a string");
    return std::nullopt;
  }
  std::string v = *n->value<std::string>();
  if (identifier) {
    if (!plain_name(v)) {
      report(key, line_of(*n), key_path(key) + " = " + show(*n) +
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
    report(key, line_, key_path(key) + " is required (one of " + list + ")");
    return std::nullopt;
  }
  auto v = string(key, false);
  if (!v) return std::nullopt;
  for (const auto& a : allowed)
    if (*v == a) return v;
  report(key, line_of(*n), key_path(key) + " = \"" + *v + "\", must be one of " + list);
  return std::nullopt;
}

std::optional<std::vector<long long>> Section::integer_array(const std::string& key, long long lo, long long hi,
                                                             bool required) {
  const std::string allowed = "must be an array of whole numbers in [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "]";
  const toml::node* n = get(key);
  if (!n) {
    if (required) report(key, line_, key_path(key) + " is required (" + allowed.substr(5) + ")");
    return std::nullopt;
  }
  const toml::array* arr = n->as_array();
  if (!arr || arr->empty()) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", " + allowed + " (not empty)");
    return std::nullopt;
  }
  std::vector<long long> out;
  for (const auto& e : *arr) {
    if (!e.is_integer() || *e.value<long long>() < lo || *e.value<long long>() > hi) {
      report(key, line_of(*n), key_path(key) + " contains " + show(e) + ", " + allowed);
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
    if (required) report(key, line_, key_path(key) + " is required (an array of numbers)");
    return std::nullopt;
  }
  const toml::array* arr = n->as_array();
  if (!arr || arr->empty()) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", must be a non-empty array of numbers");
    return std::nullopt;
  }
  std::vector<double> out;
  for (const auto& e : *arr) {
    if (!e.is_number()) {
      report(key, line_of(*n), key_path(key) + " contains " + show(e) + ", must be an array of numbers" +
                                     (e.is_array() ? " (not of arrays)" : ""));
      return std::nullopt;
    }
    const double v = *e.value<double>();
    if (!std::isfinite(v) || !range.contains(v)) {
      report(key, line_of(*n), key_path(key) + " contains " + show(e) + ", each entry " +
                                     (std::isfinite(v) ? range.describe(v) : "must be a finite number"));
      return std::nullopt;
    }
    out.push_back(*e.value<double>());
  }
  return out;
}

std::optional<std::pair<double, std::optional<double>>> Section::number_or_pair(const std::string& key,
                                                                                const Range& range, bool required) {
  const toml::node* n = table_ ? table_->get(key) : nullptr;
  if (!n || !n->is_array()) {
    const auto v = number(key, range, required);
    if (!v) return std::nullopt;
    return std::make_pair(*v, std::optional<double>());
  }
  const auto v = number_array(key, range, required);
  if (!v) return std::nullopt;
  if (v->size() != 2) {
    report(key, line_of(*n), key_path(key) + " has " + std::to_string(v->size()) +
                                 " entries, must be a number or [start, end] (two numbers, varying linearly)");
    return std::nullopt;
  }
  return std::make_pair((*v)[0], std::optional<double>((*v)[1]));
}

std::optional<std::vector<std::string>> Section::string_array(const std::string& key, bool required) {
  const toml::node* n = get(key);
  if (!n) {
    if (required) report(key, line_, key_path(key) + " is required (an array of strings)");
    return std::nullopt;
  }
  const toml::array* arr = n->as_array();
  if (!arr || arr->empty()) {
    report(key, line_of(*n), key_path(key) + " = " + show(*n) + ", must be a non-empty array of strings");
    return std::nullopt;
  }
  std::vector<std::string> out;
  for (const auto& e : *arr) {
    if (!e.is_string()) {
      report(key, line_of(*n), key_path(key) + " contains " + show(e) + ", each entry must be a string");
      return std::nullopt;
    }
    out.push_back(*e.value<std::string>());
  }
  return out;
}

std::vector<Section::RawEntry> Section::raw_entries() {
  std::vector<RawEntry> out;
  if (!table_) return out;
  for (const auto& [k, v] : *table_) {
    const std::string key(k.str());
    asked_.insert(key);
    const int line = line_of(v);
    if (v.is_string()) {
      out.push_back({key, *v.value<std::string>(), RawEntry::Kind::String, line});
    } else if (v.is_integer()) {
      out.push_back({key, std::to_string(*v.value<long long>()), RawEntry::Kind::Integer, line});
    } else if (v.is_floating_point() && !std::isfinite(*v.value<double>())) {
      problems_.mark(key_path(key));
      problems_.add(line, key_path(key) + " = " + show(v) + ", must be a finite number");
    } else if (v.is_floating_point()) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.17g", *v.value<double>());
      out.push_back({key, buf, RawEntry::Kind::Float, line});
    } else if (v.is_boolean()) {
      out.push_back({key, *v.value<bool>() ? "yes" : "no", RawEntry::Kind::Boolean, line});
    } else {
      problems_.mark(key_path(key));
      problems_.add(line, key_path(key) + " must be a string, number or boolean (it is passed to the solver)");
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const RawEntry& a, const RawEntry& b) { return a.line < b.line; });
  return out;
}

Section Section::table(const std::string& key) {
  const toml::node* n = get(key);
  if (!n) return Section(nullptr, key_path(key), problems_, line_);
  if (!n->is_table()) {
    problems_.mark(key_path(key));
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
    problems_.mark(key_path(key));
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
