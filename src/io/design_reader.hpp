#pragma once
// Validating reader over a toml++ table: every getter checks type and range, records
// a problem (with key path and line) instead of throwing, and remembers which keys it
// read so that finish() can report the unknown ones. Private to src/io.
#include <toml++/toml.h>

#include "freeflex/enum_names.hpp"

#include <limits>
#include <optional>
#include <set>
#include <utility>
#include <string>
#include <vector>

namespace freeflex::io_detail {

/// `v` in the shortest form that reads back to the same double (0.1, 1e-08, 3).
std::string shortest(double v);
/// A value as the user wrote it, numbers in shortest round-trip form; cut at 60 characters.
std::string show(const toml::node& n);
/// A name that can name a file in the output directory: 1 to 64 letters, digits, '_', '-'
/// and the characters in `also`, not starting with '.'.
bool plain_name(const std::string& v, const char* also = "");

class Problems {
 public:
  explicit Problems(std::string source) : source_(std::move(source)) {}
  void add(int line, const std::string& message);
  bool empty() const { return list_.empty(); }
  const std::vector<std::string>& list() const { return list_; }
  const std::string& source() const { return source_; }
  /// Marks a key (dotted path) whose value was rejected: what depends on it is not checked.
  void mark(const std::string& key_path) { troubled_.insert(key_path); }
  /// True if `key_path` or a table that holds it was marked.
  bool troubled(const std::string& key_path) const;

 private:
  std::string source_;
  std::set<std::string> troubled_;
  std::vector<std::string> list_;
  std::vector<int> lines_;  // line of each problem, for file order
};

/// An allowed interval for a number; bounds may be open or closed. Inside it, an optional
/// supported range [sane_lo, sane_hi] rejects magnitudes that are allowed in principle but
/// absurd in practice (a 1e300 m beam); messages name whichever rule a value breaks.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  double sane_lo = -std::numeric_limits<double>::infinity();
  double sane_hi = std::numeric_limits<double>::infinity();
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static Range nonnegative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static Range closed(double a, double b) { return {a, b, false, false}; }
  /// This range, with values outside [a, b] rejected as outside the supported range.
  Range supported(double a, double b) const {
    Range r = *this;
    r.sane_lo = a;
    r.sane_hi = b;
    return r;
  }
  bool contains(double v) const;
  std::string describe() const;          ///< "must be > 0", "must be in [1, 100]", "must be > 0, at most 1e+06"
  std::string describe(double v) const;  ///< the rule `v` breaks
};

class Section {
 public:
  /// `table` may be null (section absent); `path` is its dotted name ("" for the root).
  Section(const toml::table* table, std::string path, Problems& problems, int line);

  bool present() const { return table_ != nullptr; }
  int line() const { return line_; }
  const std::string& path() const { return path_; }
  bool has(const std::string& key) const;
  /// Line of `key` if present, else of this section.
  int line(const std::string& key) const;

  std::optional<double> number(const std::string& key, const Range& range, bool required);
  std::optional<long long> integer(const std::string& key, long long lo, long long hi, bool required);
  /// A whole number in [lo, hi], or the string `word` read as `word_value` ("all").
  std::optional<long long> integer_or_word(const std::string& key, long long lo, long long hi, const std::string& word,
                                           long long word_value, bool required);
  std::optional<bool> boolean(const std::string& key, bool required);
  /// A string; if `identifier`, only letters, digits, '_' and '-' (it names files).
  std::optional<std::string> string(const std::string& key, bool required, bool identifier = false);
  /// A string from a fixed set.
  std::optional<std::string> choice(const std::string& key, const std::vector<std::string>& allowed,
                                    bool required);
  /// A value of enum E by its name (enum_names.hpp), one of its names.
  template <class E>
  std::optional<E> enumerated(const std::string& key, bool required) {
    const auto v = choice(key, enum_names<E>(), required);
    return v ? parse_enum<E>(*v) : std::nullopt;
  }
  std::optional<std::vector<long long>> integer_array(const std::string& key, long long lo, long long hi,
                                                      bool required);
  std::optional<std::vector<std::string>> string_array(const std::string& key, bool required);
  /// An entry of a table passed through to a library: its key, its value as text (strings
  /// as written, numbers in full precision, booleans as yes/no), how it was written, and
  /// its line.
  struct RawEntry {
    enum class Kind { String, Integer, Float, Boolean };
    std::string key, text;
    Kind kind;
    int line;
  };
  /// Every entry of this table, in file order. Nested tables, arrays and non-finite numbers
  /// are problems.
  std::vector<RawEntry> raw_entries();
  std::optional<std::vector<double>> number_array(const std::string& key, const Range& range,
                                                  bool required);
  /// A number, or [start, end]: two numbers (a property varying linearly along a piece).
  /// Returns {start, end}; end is empty for a single number.
  std::optional<std::pair<double, std::optional<double>>> number_or_pair(const std::string& key, const Range& range,
                                                                         bool required);
  /// A sub-table ([beam.hub]); absent gives a Section with present() false.
  Section table(const std::string& key);
  /// An array of tables ([[beam.segment]]).
  std::vector<Section> table_array(const std::string& key);

  /// Reports every key that no getter asked for, with the keys that are allowed.
  void finish();
  /// Adds a problem at this section (or at `key`'s line if present).
  void problem(const std::string& key, const std::string& message);
  /// True once a problem has been reported at `key` (by a getter or problem()).
  bool has_problem(const std::string& key) const { return troubled_.count(key) > 0; }
  std::string key_path(const std::string& key) const;

 private:
  const toml::node* get(const std::string& key);
  void report(const std::string& key, int line, const std::string& message);  // a problem at `key`
  int line_of(const toml::node& n) const;

  const toml::table* table_;
  std::string path_;
  Problems& problems_;
  int line_;
  std::set<std::string> asked_, troubled_;
};

}  // namespace freeflex::io_detail
