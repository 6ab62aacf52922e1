// .mat files through libmatio (io/mat_file.hpp), loaded when the first file is written:
// libmatio brings HDF5 and, through it, libcurl with its TLS and Kerberos libraries, ~40
// shared libraries whose loading cost every freeflex process ~4 ms of CPU at start-up
// whether it exports or not (docs/benchmarks.md).
#include "io/mat_file.hpp"

#include <dlfcn.h>
#include <matio.h>

#include <mutex>
#include <type_traits>

#include "freeflex/io/output.hpp"

namespace freeflex::io_detail {
namespace {

/// The libmatio entry points freeflex uses.
struct Matio {
  decltype(&Mat_CreateVer) create_ver = nullptr;
  decltype(&Mat_Close) close = nullptr;
  decltype(&Mat_VarCreate) var_create = nullptr;
  decltype(&Mat_VarWrite) var_write = nullptr;
  decltype(&Mat_VarFree) var_free = nullptr;
};

/// libmatio, loaded once (FREEFLEX_MATIO_SONAME is the library freeflex was built with);
/// throws IoError when it cannot be loaded.
const Matio& matio() {
  static Matio api;
  static std::string error;
  static std::once_flag once;
  std::call_once(once, [] {
    void* lib = dlopen(FREEFLEX_MATIO_SONAME, RTLD_NOW | RTLD_LOCAL);
    const char* why = lib ? nullptr : dlerror();
    auto bind = [&](auto& fn, const char* name) {
      if (!lib) return;
      fn = reinterpret_cast<std::remove_reference_t<decltype(fn)>>(dlsym(lib, name));
      if (!fn && error.empty()) error = std::string("symbol ") + name + " not found";
    };
    bind(api.create_ver, "Mat_CreateVer");
    bind(api.close, "Mat_Close");
    bind(api.var_create, "Mat_VarCreate");
    bind(api.var_write, "Mat_VarWrite");
    bind(api.var_free, "Mat_VarFree");
    if (why) error = why;
  });
  if (!error.empty())
    throw IoError(std::string("cannot load libmatio (" FREEFLEX_MATIO_SONAME ") for the .mat export: ") + error);
  return api;
}

}  // namespace

struct MatFile::Handle {
  mat_t* mat = nullptr;
};

MatFile::MatFile(const std::string& path) : h_(std::make_unique<Handle>()), path_(path) {
  h_->mat = matio().create_ver(path.c_str(), "freeflex export (MATLAB 5.0 MAT-file)", MAT_FT_MAT5);
  if (!h_->mat) throw IoError("cannot create the MATLAB file '" + path + "'");
}

MatFile::~MatFile() {
  if (h_ && h_->mat) matio().close(h_->mat);
}

namespace {
void write_var(mat_t* mat, matvar_t* var, const std::string& name, const std::string& path) {
  if (!var) throw IoError("cannot create variable '" + name + "' in '" + path + "'");
  const int rc = matio().var_write(mat, var, MAT_COMPRESSION_NONE);
  matio().var_free(var);
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
  matvar_t* var = matio().var_create(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, static_cast<int>(d.size()), d.data(), p,
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
  matvar_t* var = matio().var_create(name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, &z, MAT_F_COMPLEX | MAT_F_DONT_COPY_DATA);
  write_var(h_->mat, var, name, path_);
}

void MatFile::add(const std::string& name, const std::string& text) {
  std::size_t dims[2] = {1, text.size()};
  std::string copy = text;
  matvar_t* var = matio().var_create(name.c_str(), MAT_C_CHAR, MAT_T_UINT8, 2, dims, copy.data(), MAT_F_DONT_COPY_DATA);
  write_var(h_->mat, var, name, path_);
}

void MatFile::close() {
  if (!h_->mat) return;
  const int rc = matio().close(h_->mat);
  h_->mat = nullptr;
  if (rc != 0) throw IoError("cannot close the MATLAB file '" + path_ + "'");
}

}  // namespace freeflex::io_detail
