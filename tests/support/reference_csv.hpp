#pragma once
// The reference tables of tests/reference, read by column name (tests/reference/README.md).
#include <catch2/catch.hpp>

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace freeflex_test {

/// Rows of tests/reference/NAME as column name → value.
inline std::vector<std::map<std::string, double>> reference_rows(const std::string& name) {
  std::ifstream in(std::string(FREEFLEX_SOURCE_DIR) + "/tests/reference/" + name);
  REQUIRE(in);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  std::stringstream hs(line);
  for (std::string c; std::getline(hs, c, ',');) header.push_back(c);
  std::vector<std::map<std::string, double>> rows;
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::map<std::string, double> row;
    std::string c;
    for (std::size_t i = 0; i < header.size() && std::getline(ls, c, ','); ++i) row[header[i]] = std::stod(c);
    rows.push_back(row);
  }
  return rows;
}

/// The same as columns: name → values in row order.
inline std::map<std::string, std::vector<double>> reference_columns(const std::string& name) {
  std::map<std::string, std::vector<double>> cols;
  for (const auto& row : reference_rows(name))
    for (const auto& [k, v] : row) cols[k].push_back(v);
  return cols;
}

}  // namespace freeflex_test
