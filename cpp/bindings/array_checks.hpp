// Shape checks shared by the bindings: a wrong shape is a ValueError naming the argument,
// the expected and the actual shape.
#pragma once

#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/status.hpp"

namespace animlod::bindings {

namespace py = pybind11;

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

inline void raise_if_error(const Status& status) {
  if (!status) throw py::value_error(status.message);
}

}  // namespace animlod::bindings
