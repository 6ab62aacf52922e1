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

namespace freeflex {

void write_file_atomic(const std::string& path, const std::function<void(std::ostream&)>& writer) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw IoError("cannot write '" + path + "': " + std::strerror(errno));
    try {
      writer(out);
    } catch (...) {
      out.close();
      std::remove(tmp.c_str());
      throw;
    }
    out.flush();
    if (!out) {
      const std::string why = std::strerror(errno);
      out.close();
      std::remove(tmp.c_str());
      throw IoError("cannot write '" + path + "': " + why);
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
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

Json Json::from(const Eigen::VectorXd& v) {
  Array a;
  for (Eigen::Index i = 0; i < v.size(); ++i) a.emplace_back(v(i));
  return Json(std::move(a));
}

Json& Json::operator[](const std::string& key) {
  if (std::holds_alternative<std::nullptr_t>(v_)) v_ = Object{};
  auto* o = std::get_if<Object>(&v_);
  if (!o) throw std::logic_error("Json: operator[] on a non-object");
  for (auto& [k, v] : *o)
    if (k == key) return v;
  o->emplace_back(key, Json());
  return o->back().second;
}

void Json::push_back(Json j) {
  if (std::holds_alternative<std::nullptr_t>(v_)) v_ = Array{};
  auto* a = std::get_if<Array>(&v_);
  if (!a) throw std::logic_error("Json: push_back on a non-array");
  a->push_back(std::move(j));
}

namespace {
void escape(std::string& out, const std::string& s) {
  out += '"';
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof buf, "\\u%04x", c);
          out += buf;
        } else {
          out += c;
        }
    }
  }
  out += '"';
}
}  // namespace

void Json::dump_to(std::string& out, int indent, int depth) const {
  const std::string pad(static_cast<std::size_t>(indent * (depth + 1)), ' ');
  const std::string pad_end(static_cast<std::size_t>(indent * depth), ' ');
  if (std::holds_alternative<std::nullptr_t>(v_)) {
    out += "null";
  } else if (auto* b = std::get_if<bool>(&v_)) {
    out += *b ? "true" : "false";
  } else if (auto* d = std::get_if<double>(&v_)) {
    if (!std::isfinite(*d)) {
      out += "null";
    } else {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.17g", *d);
      out += buf;
    }
  } else if (auto* s = std::get_if<std::string>(&v_)) {
    escape(out, *s);
  } else if (auto* a = std::get_if<Array>(&v_)) {
    bool flat = true;  // short arrays of scalars on one line
    for (const auto& e : *a) flat = flat && !std::holds_alternative<Array>(e.v_) && !std::holds_alternative<Object>(e.v_);
    out += '[';
    for (std::size_t i = 0; i < a->size(); ++i) {
      out += i ? "," : "";
      if (!flat) out += "\n" + pad;
      else if (i) out += ' ';
      (*a)[i].dump_to(out, indent, depth + 1);
    }
    if (!flat && !a->empty()) out += "\n" + pad_end;
    out += ']';
  } else if (auto* o = std::get_if<Object>(&v_)) {
    out += '{';
    for (std::size_t i = 0; i < o->size(); ++i) {
      out += i ? ",\n" : "\n";
      out += pad;
      escape(out, (*o)[i].first);
      out += ": ";
      (*o)[i].second.dump_to(out, indent, depth + 1);
    }
    if (!o->empty()) out += "\n" + pad_end;
    out += '}';
  }
}

std::string Json::dump(int indent) const {
  std::string out;
  dump_to(out, indent, 0);
  out += '\n';
  return out;
}

}  // namespace freeflex
