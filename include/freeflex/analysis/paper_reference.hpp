#pragma once
// Values printed in the paper (Kwak), kept verbatim for side-by-side comparison.
#include <optional>

namespace freeflex::paper {

/// Table 1 as printed: lambda for NOA in {2, 4, 6, 8, 10} and mode 1..4; empty where the
/// paper prints nothing (NOA = 2 has two elastic modes) or for other NOA.
std::optional<double> table1(int noa, int mode);
/// The "Exact" row as printed (its mode 4, 14.9226, is a misprint of 14.1372).
std::optional<double> table1_exact(int mode);

}  // namespace freeflex::paper
