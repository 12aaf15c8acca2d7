// CRC-32 (IEEE 802.3, zlib's crc32) of a byte range, eight bytes per step (slicing-by-8): the
// .tdag file of a long dense clip is gigabytes, and a byte at a time took seconds per gigabyte.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace animlod::detail {

// `previous`: the CRC of the bytes before (zlib's continuation), so that a file read a chunk at
// a time gets the CRC of the whole.
inline uint32_t crc32(const uint8_t* bytes, size_t size, uint32_t previous = 0) {
  static const auto tables = [] {
    std::array<std::array<uint32_t, 256>, 8> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    // t[k][i]: the CRC of byte i followed by k zero bytes.
    for (uint32_t i = 0; i < 256; ++i)
      for (size_t k = 1; k < 8; ++k) t[k][i] = (t[k - 1][i] >> 8) ^ t[0][t[k - 1][i] & 0xFFu];
    return t;
  }();
  auto word = [](const uint8_t* p) {  // little-endian whatever the machine's order
    return uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24;
  };
  uint32_t c = previous ^ 0xFFFFFFFFu;
  size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    const uint32_t low = word(bytes + i) ^ c, high = word(bytes + i + 4);
    c = tables[7][low & 0xFFu] ^ tables[6][(low >> 8) & 0xFFu] ^ tables[5][(low >> 16) & 0xFFu] ^ tables[4][low >> 24] ^
        tables[3][high & 0xFFu] ^ tables[2][(high >> 8) & 0xFFu] ^ tables[1][(high >> 16) & 0xFFu] ^
        tables[0][high >> 24];
  }
  for (; i < size; ++i) c = tables[0][(c ^ bytes[i]) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

}  // namespace animlod::detail
