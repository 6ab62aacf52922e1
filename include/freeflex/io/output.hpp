#pragma once
// Result files: atomic writes (a file appears whole or not at all) and CSV tables.
// (summary.json is nlohmann::json, app/run.hpp.)
#include <functional>
#include <ostream>
#include <stdexcept>
#include <string>
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

}  // namespace freeflex
