// Python binding of cumulative_ranking.hpp (the `cumulative` joint ranking of motion analysis).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/cumulative_ranking.hpp"
#include "array_checks.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

py::array_t<double> cumulative_freeze_steps_py(const DoubleArray& world, const DoubleArray& key_local,
                                               const py::array& parents, const MaskArray& candidates) {
  require_shape(world, "world", {-1, -1, 4, 4}, "(n, J, 4, 4)");
  const py::ssize_t joints = world.shape(1);
  require_shape(key_local, "key_local", {joints, 4, 4}, "(J, 4, 4) like world");
  const IndexArray parent_indices = index_array(parents, "parents");
  require_shape(parent_indices, "parents", {joints}, "(J,) like world");
  require_shape(candidates, "candidates", {joints}, "(J,) like world");
  py::array_t<double> out(joints);
  call_released([&] {
    return cumulative_freeze_steps(world.data(), key_local.data(), parent_indices.data(), candidates.data(),
                                   static_cast<size_t>(world.shape(0)), static_cast<size_t>(joints),
                                   out.mutable_data());
  });
  return out;
}

}  // namespace

void bind_cumulative_ranking(py::module_& m) {
  m.def("cumulative_freeze_steps", &cumulative_freeze_steps_py, py::arg("world"), py::arg("key_local"),
        py::arg("parents"), py::arg("candidates"),
        R"doc(The `cumulative` ranking's freezes: the step at which each candidate joint is frozen.

At each step the candidate whose freeze (its local transform replaced by its key frame's, with
every joint chosen before it frozen) adds least to the summed distance of the figure's points
from their original positions over the frames is frozen next; ties go to the lowest index.

Parameters
----------
world : (n, J, 4, 4) float64 world transforms of the joints at n frames (parents before children).
key_local : (J, 4, 4) float64 each joint's local transform at its key frame.
parents : (J,) int parent indices, -1 for the root.
candidates : (J,) bool joints that may freeze (never the root).

Returns
-------
(J,) float64: the step (0 first) for candidates, inf for the other joints.
Raises ValueError on a wrong shape, a parent after its child, a candidate root or a non-finite
transform (naming the element).)doc");
}

}  // namespace animlod::bindings
