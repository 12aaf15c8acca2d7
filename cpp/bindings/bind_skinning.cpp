#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/skinning.hpp"
#include "array_checks.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

// One skin's checked arrays (kept alive here) and the core's view of them. `prefix` names the
// skin in errors ("" or "others[2].").
struct SkinArrays {
  SkinArrays(const FloatArray& rest, const py::array& joint_indices, const FloatArray& weight_array,
             const FloatArray& skin_matrices, const std::string& prefix)
      : rest_positions(rest), joints(index_array(joint_indices, (prefix + "joints").c_str())), weights(weight_array) {
    require_shape(rest_positions, (prefix + "rest_positions").c_str(), {-1, 3}, "(V, 3)");
    require_shape(joints, (prefix + "joints").c_str(), {rest_positions.shape(0), -1}, "(V, K)");
    require_shape(weights, (prefix + "weights").c_str(), {joints.shape(0), joints.shape(1)}, "(V, K) like joints");
    require_shape(skin_matrices, (prefix + "skin_matrices").c_str(), {-1, -1, 4, 4}, "(T, J, 4, 4)");
    // numpy matrices act on column vectors and are stored row by row; the core takes GLM's
    // column-major layout, so transpose the small matrix array (not the big vertex arrays).
    column_major = FloatArray::ensure(skin_matrices.attr("transpose")(0, 1, 3, 2));
    input.rest_positions = rest_positions.data();
    input.joints = joints.data();
    input.weights = weights.data();
    input.skin_matrices = column_major.data();
    input.vertex_count = static_cast<size_t>(rest_positions.shape(0));
    input.influence_count = static_cast<size_t>(joints.shape(1));
    input.frame_count = static_cast<size_t>(skin_matrices.shape(0));
    input.joint_count = static_cast<size_t>(skin_matrices.shape(1));
  }

  FloatArray rest_positions;
  IndexArray joints;
  FloatArray weights, column_major;
  SkinningInput input;
};

py::array_t<float> bake_lbs_py(const FloatArray& rest_positions, const py::array& joints, const FloatArray& weights,
                               const FloatArray& skin_matrices) {
  const SkinArrays skin(rest_positions, joints, weights, skin_matrices, "");
  py::array_t<float> out({static_cast<py::ssize_t>(skin.input.frame_count), rest_positions.shape(0), py::ssize_t{3}});
  float* out_data = out.mutable_data();
  call_released([&] { return bake_lbs(skin.input, out_data); });
  return out;
}

// A skin as a tuple (rest_positions, joints, weights, skin_matrices), named `name` in errors.
SkinArrays skin_from_tuple(const py::handle& skin, const std::string& name) {
  const py::tuple arrays = py::cast<py::tuple>(skin);
  if (arrays.size() != 4)
    throw py::value_error(name + ": expected (rest_positions, joints, weights, skin_matrices), got " +
                          std::to_string(arrays.size()) + " items");
  return SkinArrays(py::cast<FloatArray>(arrays[0]), py::cast<py::array>(arrays[1]), py::cast<FloatArray>(arrays[2]),
                    py::cast<FloatArray>(arrays[3]), name + ".");
}

py::array_t<float> skin_distance_maxima_py(const py::tuple& skin, const py::sequence& others) {
  const SkinArrays a = skin_from_tuple(skin, "skin");
  std::vector<SkinArrays> kept;
  kept.reserve(others.size());
  for (size_t i = 0; i < others.size(); ++i)
    kept.push_back(skin_from_tuple(others[i], "others[" + std::to_string(i) + "]"));
  std::vector<SkinningInput> inputs;
  for (const SkinArrays& other : kept) inputs.push_back(other.input);
  py::array_t<float> out({static_cast<py::ssize_t>(inputs.size()), static_cast<py::ssize_t>(a.input.frame_count)});
  float* out_data = out.mutable_data();
  call_released([&] { return skin_distance_maxima(a.input, inputs.data(), inputs.size(), out_data); });
  return out;
}

}  // namespace

void bind_skinning(py::module_& m) {
  m.def("bake_lbs", &bake_lbs_py, py::arg("rest_positions"), py::arg("joints"), py::arg("weights"),
        py::arg("skin_matrices"),
        R"doc(Linear blend skinning of every frame, on :func:`thread_limit` threads for large inputs.

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
  m.def("skin_distance_maxima", &skin_distance_maxima_py, py::arg("skin"), py::arg("others"),
        R"doc(Per frame, the largest distance between where a skin and each of other skins of the same
vertices put a vertex.

Parameters
----------
skin : (rest_positions, joints, weights, skin_matrices) as :func:`bake_lbs` takes them.
others : N such tuples: the same V and T; K and J may differ.

Returns
-------
(N, T) float32: row n equal, bit for bit, to ``np.linalg.norm(bake_lbs(*others[n]) -
bake_lbs(*skin), axis=-1).max(axis=1)``, computed without storing the (T, V, 3) frames, on
:func:`thread_limit` threads.

Raises ValueError on a wrong shape, different V or T, or bake_lbs's errors, naming the skin.
The GIL is released.)doc");
}

}  // namespace animlod::bindings
