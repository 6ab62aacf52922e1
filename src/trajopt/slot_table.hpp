#pragma once
// A map from non-negative 64-bit keys to int slots in one flat table with linear probing,
// for the collocation Hessian's (row, column) -> slot lookups (private to src/).
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace freeflex::detail {

/// (row, column) -> slot in one flat table with linear probing: no allocation per entry
/// (std::unordered_map's node per entry cost 2% of a small maneuver's whole run).
class SlotTable {
 public:
  /// Room for `expected` entries at a load of at most a half (grows if more come).
  explicit SlotTable(std::size_t expected) {
    std::size_t cap = 64;
    while (cap < 2 * expected) cap *= 2;
    keys_.assign(cap, kEmpty);
    values_.resize(cap);
  }
  /// The slot stored for key, or -1.
  int find(long long key) const { return values_at(probe(key)); }
  /// Stores key -> value; key must not be in the table yet (find() first).
  void insert(long long key, int value) {
    if (2 * (count_ + 1) > keys_.size()) grow();
    const std::size_t i = probe(key);
    keys_[i] = key;
    values_[i] = value;
    ++count_;
  }

 private:
  static constexpr long long kEmpty = -1;
  std::size_t probe(long long key) const {
    const std::size_t mask = keys_.size() - 1;
    std::size_t i = static_cast<std::size_t>((static_cast<std::uint64_t>(key) * 0x9E3779B97F4A7C15ull) >> 20) & mask;
    while (keys_[i] != kEmpty && keys_[i] != key) i = (i + 1) & mask;
    return i;
  }
  int values_at(std::size_t i) const { return keys_[i] == kEmpty ? -1 : values_[i]; }
  void grow() {
    std::vector<long long> keys = std::move(keys_);
    std::vector<int> values = std::move(values_);
    keys_.assign(2 * keys.size(), kEmpty);
    values_.resize(keys_.size());
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) {
        const std::size_t j = probe(keys[i]);
        keys_[j] = keys[i];
        values_[j] = values[i];
      }
  }
  std::vector<long long> keys_;  ///< kEmpty: a free place (keys are r n + c >= 0)
  std::vector<int> values_;
  std::size_t count_ = 0;
};

}  // namespace freeflex::detail
