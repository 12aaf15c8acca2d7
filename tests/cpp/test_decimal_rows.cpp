#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "animlod/decimal_rows.hpp"

namespace {

// What printf writes for the same rows: the reference the lines must equal.
std::string printf_rows(const std::vector<double>& values, size_t columns, const char* prefix, int digits) {
  std::string text;
  char number[64];
  for (size_t i = 0; i < values.size(); ++i) {
    if (i % columns == 0) text += prefix;
    std::snprintf(number, sizeof number, "%.*g", digits, values[i]);
    text += number;
    text += (i % columns == columns - 1) ? "\n" : " ";
  }
  return text;
}

}  // namespace

TEST_CASE("decimal_rows: printf's %.Ng characters, for every magnitude, sign and digit count") {
  std::vector<double> values = {0.0, -0.0, 1.0, -1.0, 0.1, 1e-5, 1e-4, 123456789.0, 1234567890.0, 0.5,
                                9.9999999995, std::numeric_limits<double>::max(), std::numeric_limits<double>::min(),
                                std::numeric_limits<double>::denorm_min(), static_cast<double>(0.1f),
                                std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  std::mt19937 random(3);
  std::uniform_real_distribution<double> exponent(-40.0, 40.0);
  std::normal_distribution<float> mantissa(0.0f, 1.0f);
  while (values.size() % 3 || values.size() < 30000)  // float32 values, as the writers pass them
    values.push_back(static_cast<double>(mantissa(random) * static_cast<float>(std::pow(10.0, exponent(random)))));
  for (int digits : {1, 6, 9, 17}) {
    CHECK(animlod::decimal_rows(values.data(), values.size() / 3, 3, "v ", digits) ==
          printf_rows(values, 3, "v ", digits));
  }
  CHECK(animlod::decimal_rows(values.data(), 0, 3, "v ", 9).empty());
  CHECK(animlod::decimal_rows(values.data(), 2, 1, "", 9) == "0\n-0\n");
  CHECK_THROWS_AS(animlod::decimal_rows(values.data(), 1, 1, "", 18), std::invalid_argument);
}
