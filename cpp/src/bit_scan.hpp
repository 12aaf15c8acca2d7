// Two bit-level helpers of the collapse passes, in standard C++17 so that every compiler an
// engine builds the core with takes them (MSVC has no __builtin_ctzll or __builtin_prefetch).
#pragma once

#include <array>
#include <cstdint>

namespace animlod::detail {

// De Bruijn multiplication (Leiserson, Prokop and Randall, "Using de Bruijn Sequences to Index
// a 1 in a Computer Word", 1998): the lowest set bit times this constant has a distinct top six
// bits for each of the 64 positions.
inline constexpr uint64_t kDeBruijn64 = 0x03f79d71b4cb0a89ull;

inline constexpr std::array<uint8_t, 64> kDeBruijnPositions = [] {
  std::array<uint8_t, 64> positions{};
  for (uint8_t bit = 0; bit < 64; ++bit) positions[((uint64_t{1} << bit) * kDeBruijn64) >> 58] = bit;
  return positions;
}();

// The index of the lowest set bit of `bits`, which must not be 0.
inline int lowest_set_bit(uint64_t bits) { return kDeBruijnPositions[((bits & (~bits + 1)) * kDeBruijn64) >> 58]; }

// A hint that `address` will be read soon; nothing where the compiler has no such hint.
inline void prefetch_for_read(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(address);
#else
  (void)address;
#endif
}

}  // namespace animlod::detail
