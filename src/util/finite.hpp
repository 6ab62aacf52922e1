#pragma once
// A finiteness check for the right-hand sides' hot paths (private to src/).
#include <Eigen/Core>

namespace freeflex::util {

/// True when every entry of a is finite. x · 0 is 0 for a finite x and NaN for an infinite
/// or NaN one, so this is one vectorizable pass; Eigen's allFinite() compares x − x with
/// itself entry by entry, about ten times the instructions (3% of a TV-LQR sweep, 8% of
/// an explicit pair's right-hand side at NOA 6; docs/benchmarks.md).
template <typename Derived>
bool all_finite(const Eigen::DenseBase<Derived>& a) {
  return (a.derived().array() * 0.0).sum() == 0.0;
}

}  // namespace freeflex::util
