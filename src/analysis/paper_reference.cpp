// The paper's printed Table 1, verbatim.
#include "freeflex/analysis/paper_reference.hpp"

namespace freeflex::paper {

std::optional<double> table1(int noa, int mode) {
  static const double kTable[5][4] = {
      {4.7550, 9.0634, 0.0, 0.0},
      {4.7311, 7.8575, 11.1471, 17.2083},
      {4.7302, 7.8534, 11.0120, 14.1601},
      {4.7301, 7.8532, 10.9995, 14.1401},
      {4.7300, 7.8532, 10.9944, 14.1340},
  };
  if (noa < 2 || noa > 10 || noa % 2 != 0 || mode < 1 || mode > 4) return std::nullopt;
  const double v = kTable[noa / 2 - 1][mode - 1];
  if (v == 0.0) return std::nullopt;
  return v;
}

std::optional<double> table1_exact(int mode) {
  static const double kExact[4] = {4.7300, 7.8532, 10.9956, 14.9226};
  if (mode < 1 || mode > 4) return std::nullopt;
  return kExact[mode - 1];
}

}  // namespace freeflex::paper
