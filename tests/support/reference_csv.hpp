#pragma once
// The reference tables of tests/reference/ (computed in Python by scripts/reference/, see
// tests/reference/README.md), read by column name, and the beams they describe.
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "freeflex/model/beam.hpp"

namespace freeflex_test {

/// Column `column` of the rows of tests/reference/`file` whose `case` is `which`, in file
/// order (modes 1, 2, ...). Throws if the file, the column or the case is missing.
inline Eigen::VectorXd reference_column(const std::string& file, const std::string& which,
                                        const std::string& column = "omega_rad_s") {
  const std::string path = std::string(FREEFLEX_SOURCE_DIR) + "/tests/reference/" + file;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::string line;
  std::getline(in, line);
  auto split = [](const std::string& s) {
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string f; std::getline(ss, f, ',');) out.push_back(f);
    return out;
  };
  const std::vector<std::string> header = split(line);
  int c_case = -1, c_value = -1;
  for (int i = 0; i < static_cast<int>(header.size()); ++i) {
    if (header[i] == "case") c_case = i;
    if (header[i] == column) c_value = i;
  }
  if (c_case < 0 || c_value < 0) throw std::runtime_error(path + ": no column 'case' or '" + column + "'");
  std::vector<double> values;
  while (std::getline(in, line)) {
    const std::vector<std::string> f = split(line);
    if (static_cast<int>(f.size()) > c_value && f[c_case] == which) values.push_back(std::stod(f[c_value]));
  }
  if (values.empty()) throw std::runtime_error(path + ": no rows of case '" + which + "'");
  return Eigen::Map<Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
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
