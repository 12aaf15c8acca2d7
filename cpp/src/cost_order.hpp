// Collapse candidates ordered by cost without comparisons: a stable radix sort of the costs'
// top 33 bits (meshoptimizer's sortEdgeCollapses counts the top 12 bits of its errors and
// accepts that approximate order), then the short runs those bits leave tied ordered by the
// whole cost. The result is the comparison sort's by (cost, index), from 3 counting passes over
// 16-byte entries instead of O(n log n) comparisons and moves of the candidates themselves.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

namespace animlod::detail {

// A 64-bit key whose unsigned order is the order of `value` (-0 and +0 equal; NaN excluded).
inline uint64_t cost_order_key(double value) {
  value += 0.0;  // -0 -> +0
  uint64_t bits;
  std::memcpy(&bits, &value, sizeof bits);
  return (bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63);
}

class CostOrder {
 public:
  // Orders `items` (anything with a double `cost`) by (cost, index); order()[k] is the index of
  // the k-th. The buffers are kept for the next call.
  template <typename T>
  void sort(const std::vector<T>& items) {
    const size_t count = items.size();
    entries_.resize(count);
    moved_.resize(count);
    std::array<std::array<uint32_t, kBuckets>, kDigits> offsets{};
    for (size_t i = 0; i < count; ++i) {
      const uint64_t key = cost_order_key(items[i].cost);
      entries_[i] = {key, static_cast<uint32_t>(i)};
      for (int digit = 0; digit < kDigits; ++digit) ++offsets[digit][bucket(key, digit)];
    }
    for (int digit = 0; digit < kDigits; ++digit) {
      std::array<uint32_t, kBuckets>& offset = offsets[digit];
      if (std::find(offset.begin(), offset.end(), count) != offset.end()) continue;  // one bucket: order kept
      uint32_t sum = 0;
      for (uint32_t& start : offset) sum += std::exchange(start, sum);
      for (const Entry& entry : entries_) moved_[offset[bucket(entry.key, digit)]++] = entry;
      entries_.swap(moved_);
    }
    order_.resize(count);
    for (size_t begin = 0; begin < count;) {
      size_t end = begin + 1;
      while (end < count && (entries_[end].key ^ entries_[begin].key) >> kUnsortedBits == 0) ++end;
      if (end - begin > 1)
        std::sort(entries_.begin() + static_cast<std::ptrdiff_t>(begin),
                  entries_.begin() + static_cast<std::ptrdiff_t>(end), [](const Entry& a, const Entry& b) {
                    return a.key < b.key || (a.key == b.key && a.index < b.index);
                  });
      for (; begin < end; ++begin) order_[begin] = entries_[begin].index;
    }
  }

  const std::vector<uint32_t>& order() const { return order_; }

 private:
  struct Entry {
    uint64_t key;
    uint32_t index;
  };
  static constexpr int kDigitBits = 11, kDigits = 3, kUnsortedBits = 64 - kDigitBits * kDigits;
  static constexpr uint32_t kBuckets = 1u << kDigitBits;
  static uint32_t bucket(uint64_t key, int digit) {
    return static_cast<uint32_t>(key >> (kUnsortedBits + kDigitBits * digit)) & (kBuckets - 1);
  }

  std::vector<Entry> entries_, moved_;
  std::vector<uint32_t> order_;
};

}  // namespace animlod::detail
