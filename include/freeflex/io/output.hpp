#pragma once
// Result files: atomic writes (a file appears whole or not at all), CSV tables and a
// small JSON value type for summary.json.
#include <functional>
#include <map>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Dense>

namespace freeflex {

/// A result file or directory could not be written (exit code 3), as opposed to a
/// computation that failed.
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Writes to `path` through a temporary file in the same directory and a rename, so that
/// `path` is either the old file or the whole new one. Throws IoError naming the path and
/// the system's reason on failure.
void write_file_atomic(const std::string& path, const std::string& content);
/// The same with the content streamed by `writer` (large files are never held in memory).
void write_file_atomic(const std::string& path, const std::function<void(std::ostream&)>& writer);

/// CSV: one header line, then one line per row of `data` (shortest round-trip digits).
/// A NaN entry means "not available" and is written as an empty cell; callers check
/// computed results for NaN before they get here.
void write_csv(std::ostream& os, const std::vector<std::string>& header, const Eigen::MatrixXd& data);

/// A JSON value: null, bool, number, string, array or object (insertion-ordered).
class Json {
 public:
  using Array = std::vector<Json>;
  using Object = std::vector<std::pair<std::string, Json>>;
  Json() = default;
  Json(std::nullptr_t) {}
  Json(bool b) : v_(b) {}
  Json(int x) : v_(static_cast<double>(x)) {}
  Json(long x) : v_(static_cast<double>(x)) {}
  Json(double x) : v_(x) {}
  Json(const char* s) : v_(std::string(s)) {}
  Json(std::string s) : v_(std::move(s)) {}
  Json(Array a) : v_(std::move(a)) {}
  Json(Object o) : v_(std::move(o)) {}
  static Json array() { return Json(Array{}); }
  static Json object() { return Json(Object{}); }
  static Json from(const Eigen::VectorXd& v);

  /// Object member (added if missing); the value must be an object.
  Json& operator[](const std::string& key);
  /// Appends to an array value.
  void push_back(Json j);
  /// Pretty text; non-finite numbers are written as null (JSON has no NaN).
  std::string dump(int indent = 2) const;

 private:
  void dump_to(std::string& out, int indent, int depth) const;
  std::variant<std::nullptr_t, bool, double, std::string, Array, Object> v_{nullptr};
};

}  // namespace freeflex
