// Calls into the core from Python: the core's work runs with the GIL released, so that other
// Python threads go on and the core's workers never wait for it; a Python progress callback
// is called back with the GIL held.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>

#include <pybind11/pybind11.h>

#include "animlod/status.hpp"
#include "array_checks.hpp"

namespace animlod::bindings {

// Runs `call`, which returns a Status, with the GIL released; a failed Status is a ValueError.
template <typename Call>
void call_released(Call&& call) {
  Status status;
  {
    py::gil_scoped_release release;
    status = call();
  }
  raise_if_error(status);
}

// The core's progress callback for an optional Python callable(done, total): empty for None.
// The result holds a reference to the callable: destroy it with the GIL held.
inline std::function<void(size_t, size_t)> progress_callback(const std::optional<py::function>& progress) {
  if (!progress) return {};
  return [callback = *progress](size_t done, size_t total) {
    py::gil_scoped_acquire acquire;
    callback(done, total);
  };
}

}  // namespace animlod::bindings
