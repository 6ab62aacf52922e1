#pragma once
// MATLAB level-5 .mat files through libmatio (read by MATLAB, GNU Octave and
// scipy.io.loadmat): real and complex double arrays of any rank. Private to src/.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace freeflex::io_detail {

class MatFile {
 public:
  /// Creates `path` (replacing it). Throws IoError naming the path.
  explicit MatFile(const std::string& path);
  ~MatFile();
  MatFile(const MatFile&) = delete;
  MatFile& operator=(const MatFile&) = delete;

  /// A real matrix (rows x cols, as in MATLAB).
  void add(const std::string& name, const Eigen::MatrixXd& value);
  /// A real array of the given dimensions, column-major data (MATLAB's order).
  void add(const std::string& name, const std::vector<std::size_t>& dims, const std::vector<double>& data);
  /// A complex matrix.
  void add(const std::string& name, const Eigen::MatrixXcd& value);
  /// A character row vector.
  void add(const std::string& name, const std::string& text);
  /// Flushes and closes the file (the destructor closes it too, without reporting).
  void close();

 private:
  struct Handle;
  std::unique_ptr<Handle> h_;
  std::string path_;
};

}  // namespace freeflex::io_detail
