// The TDAG's error field (Shamir and Pascucci 2001, Section 2: a single-valued, time-tagged
// field). Bounds are 16-bit codes on a log scale; in memory a TDAG holds them as one (F, C)
// table, a row per frame, and a .tdag file stores each collapse's codes as runs: maximal ranges
// of frames with one code. A capture's bounds change nearly every frame, so runs held in memory
// cost ~12 bytes per collapse and frame against the table's 2.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace animlod::detail {

// Code 0 is 0, code q > 0 stands for scale * 2^((q - kErrorCodeZero) / kErrorCodeSteps), with
// `scale` the mesh size. Encoding rounds up, so a decoded bound is never below the bound it
// encodes (0.27% steps); encoding is monotone, so it keeps the bounds monotone up the hierarchy.
constexpr int kErrorCodeSteps = 256;
constexpr int kErrorCodeZero = 32768;
// The code of an infinite bound, and of a collapse in a frame where it is not alive (never
// collapsed there); the table's value where a collapse has no run.
constexpr uint16_t kNoCode = 65535;

inline uint16_t encode_error(double error, double scale) {
  if (!(error > 0.0)) return 0;
  if (std::isinf(error)) return kNoCode;
  const double code = std::ceil(std::log2(error / scale) * kErrorCodeSteps) + kErrorCodeZero;
  if (code < 1.0) return 1;
  if (code > double(kNoCode)) return kNoCode;
  auto q = static_cast<uint16_t>(code);
  // log2 rounding: make sure the decoded value really is >= error.
  while (q < kNoCode && std::exp2(double(q - kErrorCodeZero) / kErrorCodeSteps) * scale < error) ++q;
  return q;
}

inline double decode_error(uint16_t code, double scale) {
  if (code == 0) return 0.0;
  return scale * std::exp2(double(int(code) - kErrorCodeZero) / kErrorCodeSteps);
}

// The largest code whose bound is <= tolerance (0 for tolerance 0: only exact collapses).
inline uint16_t largest_code_within(double tolerance, double scale) {
  if (!(tolerance > 0.0)) return 0;
  uint16_t q = encode_error(tolerance, scale);
  while (q > 0 && decode_error(q, scale) > tolerance) --q;
  return q;
}

// Calls visit(birth, death, code) for each run of one collapse's codes down the frames
// (`codes[t]`, t < frame_count): the maximal ranges [birth, death) of one code other than kNoCode.
template <typename Visit>
void for_each_error_run(const uint16_t* codes, int32_t frame_count, Visit&& visit) {
  for (int32_t t = 0; t < frame_count;) {
    const uint16_t code = codes[t];
    int32_t end = t + 1;
    while (end < frame_count && codes[end] == code) ++end;
    if (code != kNoCode) visit(t, end, code);
    t = end;
  }
}

// The runs of every collapse of an (F, C) table, counted a row at a time.
inline size_t count_error_runs(const std::vector<uint16_t>& table, size_t frame_count, size_t collapse_count) {
  if (frame_count == 0) return 0;
  size_t runs = 0;
  for (size_t c = 0; c < collapse_count; ++c) runs += table[c] != kNoCode;
  for (size_t t = 1; t < frame_count; ++t) {
    const uint16_t* now = table.data() + t * collapse_count;
    const uint16_t* before = now - collapse_count;
    for (size_t c = 0; c < collapse_count; ++c) runs += now[c] != kNoCode && before[c] != now[c];
  }
  return runs;
}

// The codes of a block of consecutive collapses, collapse by collapse down the frames: a file
// stores one collapse's runs after another, and reading or writing one column of the (F, C)
// table touches a cache line per frame, which the block's kWidth columns share.
class ErrorCodeBlock {
 public:
  static constexpr size_t kWidth = 32;

  ErrorCodeBlock(size_t frame_count, size_t collapse_count)
      : frame_count_(frame_count), collapse_count_(collapse_count), codes_(kWidth * frame_count) {}

  // Collapse c's codes, for t < frame_count; c in the block last gathered or started.
  const uint16_t* column(size_t c) const { return codes_.data() + (c - first_) * frame_count_; }
  uint16_t* column(size_t c) { return codes_.data() + (c - first_) * frame_count_; }

  // Copies the block of collapse `first` out of the table.
  void gather(const std::vector<uint16_t>& table, size_t first) {
    start(first);
    for (size_t t = 0; t < frame_count_; ++t) {
      const uint16_t* row = table.data() + t * collapse_count_ + first_;
      for (size_t k = 0; k < width_; ++k) codes_[k * frame_count_ + t] = row[k];
    }
  }
  // Starts an empty block (every code kNoCode) at collapse `first`, to be filled and scattered.
  void start(size_t first) {
    first_ = first;
    width_ = std::min(kWidth, collapse_count_ - first);
    std::fill(codes_.begin(), codes_.end(), kNoCode);
  }
  // Copies the block into its place in the table.
  void scatter(std::vector<uint16_t>& table) const {
    for (size_t t = 0; t < frame_count_; ++t) {
      uint16_t* row = table.data() + t * collapse_count_ + first_;
      for (size_t k = 0; k < width_; ++k) row[k] = codes_[k * frame_count_ + t];
    }
  }

 private:
  size_t frame_count_, collapse_count_;
  size_t first_ = 0, width_ = 0;
  std::vector<uint16_t> codes_;  // (kWidth, F)
};

}  // namespace animlod::detail
