// Rows of numbers as lines of text, for the text formats the Python package writes (OBJ's v,
// vt and vn lines): Python's own formatting of each number was most of an OBJ frame's writing,
// and std::to_chars writes the same characters in a fraction of its time.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace animlod {

// `rows` lines of `columns` values each (row-major `values`): `prefix`, then each value as
// printf's "%.<digits>g" writes it ("C" locale), the values separated by one space, then '\n'.
// `digits` is 1 to 17 (9 round-trips a float32, 17 a double); another is an invalid_argument.
std::string decimal_rows(const double* values, size_t rows, size_t columns, std::string_view prefix, int digits);

}  // namespace animlod
