#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/skinning.hpp"
#include "array_checks.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

py::array_t<float> bake_lbs_py(const FloatArray& rest_positions, const py::array& joint_indices,
                               const FloatArray& weights, const FloatArray& skin_matrices) {
  require_shape(rest_positions, "rest_positions", {-1, 3}, "(V, 3)");
  const IndexArray joints = index_array(joint_indices, "joints");
  require_shape(joints, "joints", {rest_positions.shape(0), -1}, "(V, K)");
  require_shape(weights, "weights", {joints.shape(0), joints.shape(1)}, "(V, K) like joints");
  require_shape(skin_matrices, "skin_matrices", {-1, -1, 4, 4}, "(T, J, 4, 4)");

  // numpy matrices act on column vectors and are stored row by row; the core takes GLM's
  // column-major layout, so transpose the small matrix array (not the big vertex arrays).
  FloatArray column_major = FloatArray::ensure(skin_matrices.attr("transpose")(0, 1, 3, 2));
  SkinningInput input;
  input.rest_positions = rest_positions.data();
  input.joints = joints.data();
  input.weights = weights.data();
  input.skin_matrices = column_major.data();
  input.vertex_count = static_cast<size_t>(rest_positions.shape(0));
  input.influence_count = static_cast<size_t>(joints.shape(1));
  input.frame_count = static_cast<size_t>(skin_matrices.shape(0));
  input.joint_count = static_cast<size_t>(skin_matrices.shape(1));

  py::array_t<float> out({skin_matrices.shape(0), rest_positions.shape(0), py::ssize_t{3}});
  float* out_data = out.mutable_data();
  call_released([&] { return bake_lbs(input, out_data); });
  return out;
}
}  // namespace

void bind_skinning(py::module_& m) {
  m.def("bake_lbs", &bake_lbs_py, py::arg("rest_positions"), py::arg("joints"), py::arg("weights"),
        py::arg("skin_matrices"),
        R"doc(Linear blend skinning of every frame.

Parameters
----------
rest_positions : (V, 3) float32 bind-pose positions (float64 is converted).
joints : (V, K) int32 or int64 joint index per influence.
weights : (V, K) float32 influence weights, summing to 1 per vertex.
skin_matrices : (T, J, 4, 4) float32 world @ inverse_bind, numpy layout (acting on columns).

Returns
-------
(T, V, 3) float32, a new array owned by the caller (written in place by the core, no copy).

Raises ValueError on a wrong shape, a joint index outside [0, J) or a non-finite weight.
The GIL is released while skinning.)doc");
}

}  // namespace animlod::bindings
