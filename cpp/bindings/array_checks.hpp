// Array conversions and shape checks shared by the bindings: a wrong shape is a ValueError
// naming the argument, the expected and the actual shape; an index that does not fit int32 is a
// ValueError naming the argument and the element.
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/status.hpp"

namespace animlod::bindings {

namespace py = pybind11;

// Positions, weights and matrices: float32, other float dtypes converted (rounding is harmless).
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
// Solver inputs that must keep double precision (motion re-fit, lattice fits, motion analysis).
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
// Masks: one byte per element, any bool or integer dtype converted.
using MaskArray = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>;
// Indices: int32. Bindings take indices as py::array and convert them with index_array, never
// as an IndexArray argument, whose forcecast would wrap 2**32 + 5 to 5.
using IndexArray = py::array_t<int32_t, py::array::c_style | py::array::forcecast>;

// "(3, 4, 5)" for messages.
inline std::string shape_string(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// Requires a.ndim() == expected.size(); -1 in expected matches any extent.
inline void require_shape(const py::array& a, const char* name, std::initializer_list<py::ssize_t> expected,
                          const char* expected_text) {
  bool ok = a.ndim() == static_cast<py::ssize_t>(expected.size());
  py::ssize_t axis = 0;
  for (py::ssize_t extent : expected) {
    if (!ok) break;
    ok = extent < 0 || a.shape(axis) == extent;
    ++axis;
  }
  if (!ok)
    throw py::value_error(std::string(name) + ": expected shape " + expected_text + ", got " + shape_string(a));
}

namespace detail {
// "(2, 1)" for the flat element `flat` of `a`.
inline std::string element_string(const py::array& a, py::ssize_t flat) {
  std::string s;
  for (py::ssize_t axis = a.ndim() - 1; axis >= 0; --axis) {
    s = std::to_string(flat % a.shape(axis)) + (s.empty() ? "" : ", ") + s;
    flat /= a.shape(axis);
  }
  return "(" + s + (a.ndim() == 1 ? ",)" : ")");
}

// Throws ValueError at the first element of `a` (read as T) outside the int32 range.
template <typename T>
void require_int32_range(const py::array& a, const char* name) {
  const auto wide = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
  const T* values = wide.data();
  for (py::ssize_t i = 0; i < wide.size(); ++i) {
    constexpr T kLowest = std::numeric_limits<T>::is_signed ? T(std::numeric_limits<int32_t>::min()) : T(0);
    if (values[i] < kLowest || values[i] > T(std::numeric_limits<int32_t>::max()))
      throw py::value_error(std::string(name) + ": element " + element_string(a, i) + " = " +
                            std::to_string(values[i]) + " does not fit int32");
  }
}
}  // namespace detail

// int32 or int64 (any integer dtype) index array as C-contiguous int32. Wider values are
// range-checked before narrowing; a non-integer dtype is a ValueError (empty arrays pass).
inline IndexArray index_array(const py::array& a, const char* name) {
  const char kind = a.dtype().kind();
  if (a.size() > 0 && kind != 'i' && kind != 'u')
    throw py::value_error(std::string(name) + ": expected an integer array (int32 or int64), got dtype " +
                          std::string(py::str(a.dtype())));
  const bool narrow = a.size() == 0 || a.dtype().itemsize() < 4 || (kind == 'i' && a.dtype().itemsize() == 4);
  if (!narrow) {
    if (kind == 'u') detail::require_int32_range<uint64_t>(a, name);
    else detail::require_int32_range<int64_t>(a, name);
  }
  return IndexArray::ensure(a);
}

inline void raise_if_error(const Status& status) {
  if (!status) throw py::value_error(status.message);
}

}  // namespace animlod::bindings
