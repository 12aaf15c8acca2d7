// Python binding of motion_recovery.hpp (a motion level's rotations from re-fitted positions).
#include <tuple>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/motion_recovery.hpp"
#include "array_checks.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

std::tuple<py::array_t<double>, py::array_t<double>> recover_world_rotations_py(
    const py::array& parents, const MaskArray& translating, const py::array& aim_offsets,
    const py::array& aim_children, const DoubleArray& original_world, const DoubleArray& targets,
    const DoubleArray& translations) {
  const IndexArray parent_indices = index_array(parents, "parents");
  require_shape(parent_indices, "parents", {-1}, "(K,)");
  const py::ssize_t k = parent_indices.shape(0);
  require_shape(translating, "translating", {k}, "(K,) like parents");
  const IndexArray offsets = index_array(aim_offsets, "aim_offsets");
  require_shape(offsets, "aim_offsets", {k + 1}, "(K + 1,)");
  const IndexArray children = index_array(aim_children, "aim_children");
  require_shape(children, "aim_children", {-1}, "(aim_offsets[K],)");
  if (offsets.at(0) != 0 || offsets.at(k) != children.shape(0))
    throw py::value_error("aim_offsets: expected to run from 0 to len(aim_children) = " +
                          std::to_string(children.shape(0)));
  require_shape(original_world, "original_world", {-1, k, 4}, "(T, K, 4)");
  const py::ssize_t frames = original_world.shape(0);
  require_shape(targets, "targets", {frames, k, 3}, "(T, K, 3) like original_world");
  require_shape(translations, "translations", {frames, k, 3}, "(T, K, 3) like original_world");
  py::array_t<double> recovered_translations({frames, k, py::ssize_t{3}});
  std::copy(translations.data(), translations.data() + translations.size(), recovered_translations.mutable_data());
  py::array_t<double> world({frames, k, py::ssize_t{4}});
  const AimedSkeleton skeleton{parent_indices.data(), translating.data(), offsets.data(), children.data(),
                               static_cast<size_t>(k)};
  call_released([&] {
    return recover_world_rotations(skeleton, static_cast<size_t>(frames), original_world.data(), targets.data(),
                                   recovered_translations.mutable_data(), world.mutable_data());
  });
  return {world, recovered_translations};
}

}  // namespace

void bind_motion_recovery(py::module_& m) {
  m.def("recover_world_rotations", &recover_world_rotations_py, py::arg("parents"), py::arg("translating"),
        py::arg("aim_offsets"), py::arg("aim_children"), py::arg("original_world"), py::arg("targets"),
        py::arg("translations"),
        R"doc(World rotations of a motion level recovered from re-fitted positions, every frame at once.

Per frame, in joint order, a root is placed at its target and any other joint by forward
kinematics from its parent (a translating joint first takes the translation that puts it at its
target), and its original world rotation is corrected by the rotation that aims its children
from there at their targets: the swing towards its one aim child, the best-fit rotation (Kabsch)
of several.

Parameters
----------
parents : (K,) int, -1 for a root (placed at its target), parents before children.
translating : (K,) bool joints with no fixed bone.
aim_offsets, aim_children : each joint's aim children, aim_children[aim_offsets[j]:aim_offsets[j + 1]].
original_world : (T, K, 4) float64 unit quaternions (x, y, z, w), the original world rotations.
targets : (T, K, 3) float64 re-fitted positions.
translations : (T, K, 3) float64 offsets in the parents' frames.

Returns
-------
(world (T, K, 4), translations (T, K, 3)): the recovered world rotations, and the offsets with
the translating joints' recovered. Raises ValueError on a wrong shape, a bad parent or aim child
or a non-finite value (naming the element).)doc");
}

}  // namespace animlod::bindings
