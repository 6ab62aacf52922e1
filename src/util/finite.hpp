#pragma once
// A finiteness check for the right-hand sides' hot paths (private to src/).
#include <Eigen/Core>

namespace freeflex::util {

/// True when every entry of a is finite (true for no entries). x · 0 is ±0 for a finite x
/// and NaN for an infinite or NaN one, so the sum is 0 or NaN and cannot overflow: one
/// vectorizable pass, where Eigen's allFinite() compares x − x with itself entry by entry
/// (7.3 M of the 229 M instructions of the NOA-6 TV-LQR sweep; docs/benchmarks.md).
template <typename Derived>
bool all_finite(const Eigen::DenseBase<Derived>& a) {
  return (a.derived().array() * 0.0).sum() == 0.0;
}

}  // namespace freeflex::util
