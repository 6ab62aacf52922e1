// .mat files through libmatio (io/mat_file.hpp).
#include "io/mat_file.hpp"

#include <matio.h>

#include "freeflex/io/output.hpp"

namespace freeflex::io_detail {

struct MatFile::Handle {
  mat_t* mat = nullptr;
};

MatFile::MatFile(const std::string& path) : h_(std::make_unique<Handle>()), path_(path) {
  h_->mat = Mat_CreateVer(path.c_str(), "freeflex export (MATLAB 5.0 MAT-file)", MAT_FT_MAT5);
  if (!h_->mat) throw IoError("cannot create the MATLAB file '" + path + "'");
}

MatFile::~MatFile() {
  if (h_ && h_->mat) Mat_Close(h_->mat);
}

namespace {
void write_var(mat_t* mat, matvar_t* var, const std::string& name, const std::string& path) {
  if (!var) throw IoError("cannot create variable '" + name + "' in '" + path + "'");
  const int rc = Mat_VarWrite(mat, var, MAT_COMPRESSION_NONE);
  Mat_VarFree(var);
  if (rc != 0) throw IoError("cannot write variable '" + name + "' to '" + path + "'");
}
}  // namespace

void MatFile::add(const std::string& name, const std::vector<std::size_t>& dims, const std::vector<double>& data) {
  std::vector<std::size_t> d = dims;
  while (d.size() < 2) d.push_back(1);
  std::size_t count = 1;
  for (std::size_t x : d) count *= x;
  if (count != data.size()) throw std::logic_error("MatFile::add: dimensions do not match the data of " + name);
  static double empty = 0.0;
  void* p = data.empty() ? static_cast<void*>(&empty) : const_cast<double*>(data.data());
  matvar_t* var = Mat_VarCreate(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, static_cast<int>(d.size()), d.data(), p,
                                MAT_F_DONT_COPY_DATA);
  write_var(h_->mat, var, name, path_);
}

void MatFile::add(const std::string& name, const Eigen::MatrixXd& value) {
  std::vector<double> data(value.data(), value.data() + value.size());
  add(name, {static_cast<std::size_t>(value.rows()), static_cast<std::size_t>(value.cols())}, data);
}

void MatFile::add(const std::string& name, const Eigen::MatrixXcd& value) {
  Eigen::MatrixXd re = value.real(), im = value.imag();
  std::size_t dims[2] = {static_cast<std::size_t>(value.rows()), static_cast<std::size_t>(value.cols())};
  mat_complex_split_t z{re.data(), im.data()};
  matvar_t* var = Mat_VarCreate(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, &z, MAT_F_COMPLEX | MAT_F_DONT_COPY_DATA);
  write_var(h_->mat, var, name, path_);
}

void MatFile::add(const std::string& name, const std::string& text) {
  std::size_t dims[2] = {1, text.size()};
  std::string copy = text;
  matvar_t* var = Mat_VarCreate(name.c_str(), MAT_C_CHAR, MAT_T_UINT8, 2, dims, copy.data(), MAT_F_DONT_COPY_DATA);
  write_var(h_->mat, var, name, path_);
}

void MatFile::close() {
  if (!h_->mat) return;
  const int rc = Mat_Close(h_->mat);
  h_->mat = nullptr;
  if (rc != 0) throw IoError("cannot close the MATLAB file '" + path_ + "'");
}

}  // namespace freeflex::io_detail
