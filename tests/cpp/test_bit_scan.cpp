#include <doctest/doctest.h>

#include <cstdint>
#include <random>

#include "bit_scan.hpp"

using animlod::detail::lowest_set_bit;

namespace {

int lowest_set_bit_by_loop(uint64_t bits) {
  int index = 0;
  while ((bits & 1) == 0) bits >>= 1, ++index;
  return index;
}

}  // namespace

TEST_CASE("lowest set bit: every single bit, and every bit under random higher ones") {
  for (int bit = 0; bit < 64; ++bit) CHECK(lowest_set_bit(uint64_t{1} << bit) == bit);
  CHECK(lowest_set_bit(~uint64_t{0}) == 0);
  std::mt19937_64 random(7);
  for (int trial = 0; trial < 10000; ++trial) {
    const uint64_t bits = random() | (uint64_t{1} << (trial % 64));
    CHECK(lowest_set_bit(bits) == lowest_set_bit_by_loop(bits));
  }
}
