// Hands a result vector to numpy without copying: the vector moves into a heap object that a
// capsule owns, and the array is a view of its buffer (freed when the array is).
#pragma once

#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace animlod::bindings {

namespace py = pybind11;

template <typename T>
py::array_t<T> numpy_from_vector(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule owner(owned, [](void* pointer) { delete static_cast<std::vector<T>*>(pointer); });
  return py::array_t<T>(std::move(shape), owned->data(), owner);
}

}  // namespace animlod::bindings
