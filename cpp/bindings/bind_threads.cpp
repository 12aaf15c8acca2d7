#include <pybind11/pybind11.h>

#include "animlod/threads.hpp"

namespace py = pybind11;

namespace animlod::bindings {

void bind_threads(py::module_& m) {
  m.def("set_thread_limit", &set_thread_limit, py::arg("threads"),
        R"doc(Caps the threads of every parallel loop of the core, process-wide (0: every hardware thread,
the default; the environment variable ANIMLOD_THREADS sets the starting cap). Results never
depend on it.)doc");
  m.def("thread_limit", &thread_limit,
        R"doc(The threads a parallel loop of the core may take now: the cap, at most the hardware threads,
at least 1.)doc");
  m.def("thread_environment_ignored", &thread_environment_ignored,
        R"doc(True when ANIMLOD_THREADS is set to something other than a whole number, which the core
ignores.)doc");
}

}  // namespace animlod::bindings
