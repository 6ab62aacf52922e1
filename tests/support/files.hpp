#pragma once
// A whole file as text, for the tests that check what a run or a figure wrote.
#include <fstream>
#include <sstream>
#include <string>

namespace freeflex_test {

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace freeflex_test
