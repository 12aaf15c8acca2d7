#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "../../cpp/src/tdag_error_codes.hpp"

using animlod::detail::ErrorCodeBlock;
using animlod::detail::kNoCode;

namespace {

struct Run {
  int32_t birth, death;
  uint16_t code;
  bool operator==(const Run& o) const { return birth == o.birth && death == o.death && code == o.code; }
};

std::vector<Run> runs_of(const std::vector<uint16_t>& codes) {
  std::vector<Run> out;
  animlod::detail::for_each_error_run(codes.data(), static_cast<int32_t>(codes.size()),
                                      [&](int32_t birth, int32_t death, uint16_t code) { out.push_back({birth, death, code}); });
  return out;
}

// An (F, C) table of codes that change now and then, with frames where a collapse has none.
std::vector<uint16_t> random_table(size_t frames, size_t collapses, uint32_t seed) {
  std::mt19937 random(seed);
  std::vector<uint16_t> table(frames * collapses);
  for (size_t c = 0; c < collapses; ++c) {
    uint16_t code = 40000;
    for (size_t t = 0; t < frames; ++t) {
      const uint32_t roll = random() % 8;
      if (roll == 0) code = kNoCode;
      else if (roll < 3) code = static_cast<uint16_t>(30000 + random() % 5);
      table[t * collapses + c] = code;
    }
  }
  return table;
}

}  // namespace

TEST_CASE("tdag error codes: runs are the maximal ranges of one code, frames without a code end them") {
  CHECK(runs_of({5, 5, kNoCode, kNoCode, 7, 7, 7, 5}) == std::vector<Run>{{0, 2, 5}, {4, 7, 7}, {7, 8, 5}});
  CHECK(runs_of({kNoCode, 3}) == std::vector<Run>{{1, 2, 3}});
  CHECK(runs_of({9}) == std::vector<Run>{{0, 1, 9}});
  CHECK(runs_of({kNoCode, kNoCode}).empty());
  CHECK(runs_of({}).empty());
}

TEST_CASE("tdag error codes: the table's runs counted by rows equal each column's, blocks round trip the table") {
  for (const auto& [frames, collapses] : std::vector<std::array<size_t, 2>>{{1, 1}, {17, 70}, {64, 32}, {5, 100}}) {
    CAPTURE(frames);
    CAPTURE(collapses);
    const std::vector<uint16_t> table = random_table(frames, collapses, static_cast<uint32_t>(frames * 1000 + collapses));
    ErrorCodeBlock block(frames, collapses);
    std::vector<uint16_t> scattered(table.size(), 0);
    size_t runs = 0;
    for (size_t first = 0; first < collapses; first += ErrorCodeBlock::kWidth) {
      block.gather(table, first);
      for (size_t c = first; c < std::min(collapses, first + ErrorCodeBlock::kWidth); ++c) {
        std::vector<uint16_t> column(frames);
        for (size_t t = 0; t < frames; ++t) column[t] = table[t * collapses + c];
        CHECK(std::vector<uint16_t>(block.column(c), block.column(c) + frames) == column);
        runs += runs_of(column).size();
      }
      ErrorCodeBlock copy(frames, collapses);
      copy.start(first);
      for (size_t c = first; c < std::min(collapses, first + ErrorCodeBlock::kWidth); ++c)
        std::copy_n(block.column(c), frames, copy.column(c));
      copy.scatter(scattered);
    }
    CHECK(scattered == table);
    CHECK(animlod::detail::count_error_runs(table, frames, collapses) == runs);
  }
}
