// Result files: atomic writes and CSV tables (io/output.hpp).
#include "freeflex/io/output.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

#include "io/system_error.hpp"

namespace freeflex {

void write_file_atomic(const std::string& path, const std::function<void(std::ostream&)>& writer) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError("cannot write '" + path + "': " + io_detail::reason(errno));
    try {
      writer(out);
    } catch (...) {
      out.close();
      std::remove(tmp.c_str());
      throw;
    }
    out.flush();
    if (!out) {
      const std::string why = io_detail::reason(errno);
      out.close();
      std::remove(tmp.c_str());
      throw IoError("cannot write '" + path + "': " + why);
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = io_detail::reason(errno);
    std::remove(tmp.c_str());
    throw IoError("cannot write '" + path + "': " + why);
  }
}

void write_file_atomic(const std::string& path, const std::string& content) {
  write_file_atomic(path, [&content](std::ostream& os) { os << content; });
}

void write_csv(std::ostream& os, const std::vector<std::string>& header, const Eigen::MatrixXd& data) {
  if (static_cast<Eigen::Index>(header.size()) != data.cols())
    throw std::invalid_argument("write_csv: expected " + std::to_string(data.cols()) + " column names, got " +
                                std::to_string(header.size()));
  for (std::size_t j = 0; j < header.size(); ++j) os << (j ? "," : "") << header[j];
  os << '\n';
  std::string line;
  for (Eigen::Index i = 0; i < data.rows() && os; ++i) {
    line.clear();
    for (Eigen::Index j = 0; j < data.cols(); ++j) {
      if (j) line += ',';
      if (!std::isnan(data(i, j))) {
        char buf[32];  // shortest text that reads back to the same double
        const auto res = std::to_chars(buf, buf + sizeof buf, data(i, j));
        line.append(buf, res.ptr);
      }  // NaN marks "not available": empty cell
    }
    line += '\n';
    os.write(line.data(), static_cast<std::streamsize>(line.size()));
  }
}

}  // namespace freeflex
