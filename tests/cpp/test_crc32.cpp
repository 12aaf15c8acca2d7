#include <doctest/doctest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "../../cpp/src/crc32.hpp"

namespace {

uint32_t crc32_bytewise(const uint8_t* bytes, size_t size) {  // the textbook bit loop
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) {
    c ^= bytes[i];
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

}  // namespace

TEST_CASE("crc32: the standard check value, and the bit loop's value at every length and offset") {
  const std::string check = "123456789";
  CHECK(animlod::detail::crc32(reinterpret_cast<const uint8_t*>(check.data()), check.size()) == 0xCBF43926u);
  CHECK(animlod::detail::crc32(nullptr, 0) == 0u);
  std::mt19937 random(5);
  std::vector<uint8_t> bytes(100);
  for (uint8_t& b : bytes) b = static_cast<uint8_t>(random());
  for (size_t offset = 0; offset < 8; ++offset)
    for (size_t size = 0; offset + size <= bytes.size(); ++size)
      REQUIRE(animlod::detail::crc32(bytes.data() + offset, size) == crc32_bytewise(bytes.data() + offset, size));
}

TEST_CASE("crc32: continued over two pieces, the CRC of the whole at every split") {
  std::mt19937 random(7);
  std::vector<uint8_t> bytes(50);
  for (uint8_t& b : bytes) b = static_cast<uint8_t>(random());
  const uint32_t whole = animlod::detail::crc32(bytes.data(), bytes.size());
  for (size_t split = 0; split <= bytes.size(); ++split)
    REQUIRE(animlod::detail::crc32(bytes.data() + split, bytes.size() - split,
                                   animlod::detail::crc32(bytes.data(), split)) == whole);
}
