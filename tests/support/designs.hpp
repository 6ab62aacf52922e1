#pragma once
// Design texts and the problems a design file has, for the tests of the design reader.
#include <string>

#include "freeflex/io/design.hpp"

namespace freeflex_test {

/// The problems of a design text as DesignError lists them ("" when it loads).
inline std::string problems_of(const std::string& text) {
  try {
    freeflex::parse_design(text, "t.toml");
  } catch (const freeflex::DesignError& e) {
    return e.what();
  }
  return "";
}

/// A small valid design.
inline const char* kGood = R"(title = "ok"
[beam]
length_m = 2.0
mass_kg = 3.0
bending_stiffness_Nm2 = 5.0
[model]
noa = 8
)";

inline const std::string kPaperBeam = "[beam]\nlength_m = 1.0\nmass_kg = 1.0\nbending_stiffness_Nm2 = 1.0\n";  // lines 1-4
inline const std::string kLoad =  // lines 5-13
    "[[load]]\nname = \"F\"\ntype = \"force\"\nposition_m = 0.5\ndirection = [0.0, 1.0]\n"
    "[load.profile]\ntype = \"steps\"\ntimes_s = [0.0, 0.5, 1.0]\nvalues = [1.0, -1.0]\n";

/// s repeated n times (designs at and past a size bound).
inline std::string repeated(const std::string& s, int n) {
  std::string r;
  for (int i = 0; i < n; ++i) r += s;
  return r;
}

}  // namespace freeflex_test
