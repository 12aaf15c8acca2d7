#include "animlod/decimal_rows.hpp"

#include <charconv>
#include <stdexcept>
#include <system_error>

namespace animlod {

std::string decimal_rows(const double* values, size_t rows, size_t columns, std::string_view prefix, int digits) {
  if (digits < 1 || digits > 17) throw std::invalid_argument("decimal_rows: digits must be 1 to 17");
  // "%.17g" takes at most 24 characters ("-1.2345678901234567e-308"), and a separator.
  constexpr size_t widest_value = 25;
  std::string text(rows * (prefix.size() + columns * widest_value + 1), '\0');
  char* out = text.data();
  char* const end = out + text.size();
  for (size_t row = 0; row < rows; ++row) {
    out += prefix.copy(out, prefix.size());
    for (size_t column = 0; column < columns; ++column) {
      if (column) *out++ = ' ';
      out = std::to_chars(out, end, values[row * columns + column], std::chars_format::general, digits).ptr;
    }
    *out++ = '\n';
  }
  text.resize(static_cast<size_t>(out - text.data()));
  return text;
}

}  // namespace animlod
