// Collapse candidates ordered by cost without comparisons, and only as far as they are read. One
// counting pass distributes the candidates by their costs' top 16 bits (sign, exponent and 4
// mantissa bits); a bucket is ordered when the order is first read inside it, by a stable radix
// sort of the next 22 bits in cache, then the short runs those bits leave tied by the whole cost
// (meshoptimizer's sortEdgeCollapses counts the top 12 bits and accepts that approximate order).
// A collapse pass reads its candidates only up to its cost bound, so the dearer ones are never
// ordered. The result is the comparison sort's by (cost, index).
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "worker_threads.hpp"

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
  // Takes the costs of `items` (anything with a double `cost`) and distributes them by their top
  // bits; (*this)[k] is then the index of the k-th item by (cost, index). The buffers are kept
  // for the next call.
  template <typename T>
  void sort(const std::vector<T>& items) {
    const size_t count = items.size();
    distributed_.resize(count);
    bucket_ends_.clear();
    next_bucket_ = ordered_ = 0;
    // Two workers for many items, each counting and then placing its half of them (the first
    // half's entries first in every bucket, as one worker places them).
    const size_t workers = halves_from(count, kTwoWorkersFrom);
    for (size_t worker = 0; worker < workers; ++worker) offsets_[worker].assign(kTopBuckets, 0);
    run_in_ranges(count, workers, [&](size_t begin, size_t end, size_t worker) {
      std::vector<uint32_t>& offset = offsets_[worker];
      for (size_t i = begin; i < end; ++i) ++offset[top_bucket(cost_order_key(items[i].cost))];
    });
    uint32_t sum = 0;
    for (uint32_t bucket = 0; bucket < kTopBuckets; ++bucket) {
      const uint32_t start = sum;
      for (size_t worker = 0; worker < workers; ++worker) sum += std::exchange(offsets_[worker][bucket], sum);
      if (sum > start) bucket_ends_.push_back(sum);
    }
    run_in_ranges(count, workers, [&](size_t begin, size_t end, size_t worker) {
      std::vector<uint32_t>& offset = offsets_[worker];
      for (size_t i = begin; i < end; ++i) {
        const uint64_t key = cost_order_key(items[i].cost);
        distributed_[offset[top_bucket(key)]++] = {key, static_cast<uint32_t>(i)};
      }
    });
  }

  size_t size() const { return distributed_.size(); }

  uint32_t operator[](size_t k) {
    assert(k < size());
    while (k >= ordered_) order_next_bucket();
    return distributed_[k].index;
  }

  // The index of the k-th item if its bucket is ordered already, without ordering any (to
  // prefetch what the k-th will read); -1 otherwise.
  int64_t ordered_index(size_t k) const { return k < ordered_ ? distributed_[k].index : -1; }

 private:
  struct Entry {
    uint64_t key;
    uint32_t index;
  };
  static constexpr int kTopBits = 16, kDigitBits = 11, kDigits = 2;
  static constexpr int kUnsortedBits = 64 - kTopBits - kDigitBits * kDigits;
  static constexpr uint32_t kTopBuckets = 1u << kTopBits, kBuckets = 1u << kDigitBits;
  static constexpr size_t kComparisonSortBelow = 256;  // fewer entries: a comparison sort is cheaper
  static constexpr size_t kTwoWorkersFrom = 1 << 18;    // fewer items are distributed on one thread
  static uint32_t top_bucket(uint64_t key) { return static_cast<uint32_t>(key >> (64 - kTopBits)); }
  static uint32_t bucket(uint64_t key, int digit) {
    return static_cast<uint32_t>(key >> (kUnsortedBits + kDigitBits * digit)) & (kBuckets - 1);
  }
  static bool less(const Entry& a, const Entry& b) { return a.key < b.key || (a.key == b.key && a.index < b.index); }

  // Orders the next top-bits bucket in place; entries within it are in index order so far.
  void order_next_bucket() {
    const auto begin = distributed_.begin() + static_cast<std::ptrdiff_t>(ordered_);
    const size_t count = bucket_ends_[next_bucket_++] - ordered_;
    const auto end = begin + static_cast<std::ptrdiff_t>(count);
    ordered_ += count;
    if (count < kComparisonSortBelow) {
      std::sort(begin, end, less);
      return;
    }
    std::array<std::array<uint32_t, kBuckets>, kDigits> offsets{};
    for (auto entry = begin; entry != end; ++entry)
      for (int digit = 0; digit < kDigits; ++digit) ++offsets[digit][bucket(entry->key, digit)];
    moved_.resize(count);
    Entry *source = &*begin, *target = moved_.data();
    for (int digit = 0; digit < kDigits; ++digit) {
      std::array<uint32_t, kBuckets>& offset = offsets[digit];
      if (std::find(offset.begin(), offset.end(), count) != offset.end()) continue;  // one bucket: order kept
      uint32_t sum = 0;
      for (uint32_t& start : offset) sum += std::exchange(start, sum);
      for (const Entry* entry = source; entry != source + count; ++entry)
        target[offset[bucket(entry->key, digit)]++] = *entry;
      std::swap(source, target);
    }
    if (source != &*begin) std::copy(source, source + count, begin);
    for (auto run = begin; run != end;) {
      auto run_end = run + 1;
      while (run_end != end && (run_end->key ^ run->key) >> kUnsortedBits == 0) ++run_end;
      if (run_end - run > 1) std::sort(run, run_end, less);
      run = run_end;
    }
  }

  std::vector<Entry> distributed_, moved_;
  std::array<std::vector<uint32_t>, 2> offsets_;  // per worker: its count, then its next place, per top bucket
  std::vector<uint32_t> bucket_ends_;  // exclusive end in distributed_ of each non-empty bucket
  size_t next_bucket_ = 0;
  size_t ordered_ = 0;  // distributed_[0, ordered_) is in order
};

}  // namespace animlod::detail
