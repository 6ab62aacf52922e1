#pragma once
// The reference tables of tests/reference/ (computed in Python by scripts/reference/, see
// tests/reference/README.md), read by column name, and the beams they describe.
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/model/beam.hpp"

namespace freeflex_test {

/// The text of tests/reference/`file`: its header's column names and its rows' cells, as
/// written. Throws if the file cannot be read.
struct ReferenceTable {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  /// Index of column `name`, or -1.
  int column(const std::string& name) const {
    for (int i = 0; i < static_cast<int>(header.size()); ++i)
      if (header[i] == name) return i;
    return -1;
  }
};

inline ReferenceTable read_reference(const std::string& file) {
  ReferenceTable t;
  t.path = std::string(FREEFLEX_SOURCE_DIR) + "/tests/reference/" + file;
  std::ifstream in(t.path);
  if (!in) throw std::runtime_error("cannot read " + t.path);
  auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string f; std::getline(ss, f, ',');) out.push_back(f);
    return out;
  };
  std::string line;
  std::getline(in, line);
  t.header = split(line);
  while (std::getline(in, line))
    if (!line.empty()) t.rows.push_back(split(line));
  return t;
}

/// Column `column` of the rows of tests/reference/`file` whose `case` is `which`, in file
/// order (modes 1, 2, ...). Throws if the file, the column or the case is missing.
inline Eigen::VectorXd reference_column(const std::string& file, const std::string& which,
                                        const std::string& column = "omega_rad_s") {
  const ReferenceTable t = read_reference(file);
  const int c_case = t.column("case"), c_value = t.column(column);
  if (c_case < 0 || c_value < 0) throw std::runtime_error(t.path + ": no column 'case' or '" + column + "'");
  std::vector<double> values;
  for (const auto& f : t.rows)
    if (static_cast<int>(f.size()) > c_value && f[c_case] == which) values.push_back(std::stod(f[c_value]));
  if (values.empty()) throw std::runtime_error(t.path + ": no rows of case '" + which + "'");
  return Eigen::Map<Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
}

/// Rows of an all-numeric tests/reference/`file` as column name → value. Throws if the
/// file is missing or a cell is not a number.
inline std::vector<std::map<std::string, double>> reference_rows(const std::string& file) {
  const ReferenceTable t = read_reference(file);
  std::vector<std::map<std::string, double>> rows;
  for (const auto& f : t.rows) {
    std::map<std::string, double> row;
    for (std::size_t i = 0; i < t.header.size() && i < f.size(); ++i) row[t.header[i]] = std::stod(f[i]);
    rows.push_back(row);
  }
  return rows;
}

/// The same as columns: name → values in row order.
inline std::map<std::string, std::vector<double>> reference_columns(const std::string& file) {
  std::map<std::string, std::vector<double>> cols;
  for (const auto& row : reference_rows(file))
    for (const auto& [k, v] : row) cols[k].push_back(v);
  return cols;
}

/// The stepped beam of issue 15 (tests/reference/README.md section A): 0.6 m at 1.2 kg/m,
/// EI 2 N m², then 0.4 m at 0.6 kg/m, EI 0.8 N m²; with `payloads`, a hub of 0.3 kg and
/// 0.002 kg m² at s = 0.5 m (o there) and 0.1 kg at the tip s = 1 m.
inline freeflex::BeamProperties stepped_beam(bool payloads) {
  freeflex::BeamProperties p;
  p.segments = {{0.6, 1.2, 2.0}, {0.4, 0.6, 0.8}};
  if (payloads) {
    p.reference_m = 0.5;
    p.hub_mass_kg = 0.3;
    p.hub_rotary_inertia_kgm2 = 0.002;
    p.point_masses = {{1.0, 0.1}};
  }
  return p;
}

/// The tapered beam of tests/reference/README.md section B: L = 1 m, m(s) = 1.2 - 0.8 s
/// kg/m, EI(s) = 2 - 1.5 s N m²; with `tip`, 0.05 kg at s = 1 m.
inline freeflex::BeamProperties tapered_beam(bool tip) {
  freeflex::BeamProperties p;
  freeflex::BeamSegment s{1.0, 1.2, 2.0};
  s.mass_per_length_end_kg_m = 0.4;
  s.bending_stiffness_end_Nm2 = 0.5;
  p.segments = {s};
  if (tip) p.point_masses = {{1.0, 0.05}};
  return p;
}

}  // namespace freeflex_test
