// Python bindings of pose.hpp: the keyframe sampler, forward kinematics and the skinning
// palette, vectorised over sample times / frames. Matrices cross the boundary in numpy's layout
// ((..., 4, 4) acting on column vectors, stored row by row) and are transposed to GLM's
// column-major layout on the way in and out.
#include <optional>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "animlod/pose.hpp"
#include "array_checks.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

Interpolation interpolation_from(const std::string& name) {
  if (name == "LINEAR") return Interpolation::linear;
  if (name == "STEP") return Interpolation::step;
  if (name == "CUBICSPLINE") return Interpolation::cubic_spline;
  throw py::value_error("interpolation: expected LINEAR, STEP or CUBICSPLINE, got " + name);
}

RotationBlend blend_from(const std::string& name) {
  if (name == "slerp") return RotationBlend::slerp;
  if (name == "nlerp") return RotationBlend::nlerp;
  throw py::value_error("blend: expected slerp or nlerp, got " + name);
}

// (n, 4, 4) numpy-layout matrices <-> (n, 16) column-major: the same transpose either way.
void transpose_matrices(const float* in, size_t count, float* out) {
  for (size_t m = 0; m < count; ++m)
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) out[16 * m + 4 * c + r] = in[16 * m + 4 * r + c];
}

py::array_t<float> sample_keyframes_py(const FloatArray& times, const FloatArray& values, const std::string& interpolation,
                                       const FloatArray& at, bool rotation, const std::string& blend) {
  KeyframeTrack track;
  track.interpolation = interpolation_from(interpolation);
  require_shape(times, "times", {-1}, "(N,)");
  require_shape(at, "at", {-1}, "(T,)");
  if (track.interpolation == Interpolation::cubic_spline)
    require_shape(values, "values", {times.shape(0), 3, -1}, "(N, 3, C) for CUBICSPLINE");
  else
    require_shape(values, "values", {times.shape(0), -1}, "(N, C)");
  track.times = times.data();
  track.values = values.data();
  track.key_count = static_cast<size_t>(times.shape(0));
  track.component_count = static_cast<size_t>(values.shape(values.ndim() - 1));
  raise_if_error(validate_track(track, rotation));
  const RotationBlend mode = blend_from(blend);
  const py::ssize_t count = at.shape(0), components = values.shape(values.ndim() - 1);
  py::array_t<float> out({count, components});
  float* data = out.mutable_data();
  const float* when = at.data();
  {
    py::gil_scoped_release release;
    for (py::ssize_t t = 0; t < count; ++t) sample_track(track, when[t], rotation, mode, data + t * components);
  }
  return out;
}

// A list or array of indices as an array (index_array checks the dtype).
py::array as_array(const py::object& values, const char* name) {
  py::array array = py::array::ensure(values);
  if (!array) throw py::value_error(std::string(name) + ": expected an integer array");
  return array;
}

// The parents (J,) of T poses, checked with their translations (T, J, 3) and rotations (T, J, 4).
template <typename Array>
IndexArray pose_parents(const py::object& parent_indices, const Array& translations, const Array& rotations) {
  IndexArray parents = index_array(as_array(parent_indices, "parents"), "parents");
  require_shape(parents, "parents", {-1}, "(J,)");
  require_shape(translations, "translations", {-1, parents.shape(0), 3}, "(T, J, 3)");
  require_shape(rotations, "rotations", {translations.shape(0), parents.shape(0), 4}, "(T, J, 4) like translations");
  return parents;
}

py::array_t<float> forward_kinematics_py(const py::object& parent_indices, const FloatArray& translations,
                                         const FloatArray& rotations, const std::optional<FloatArray>& scales) {
  const IndexArray parents = pose_parents(parent_indices, translations, rotations);
  const py::ssize_t joints = parents.shape(0), frames = translations.shape(0);
  if (scales) require_shape(*scales, "scales", {frames, joints, 3}, "(T, J, 3) like translations");
  raise_if_error(validate_parents(parents.data(), static_cast<size_t>(joints)));

  py::array_t<float> out({frames, joints, py::ssize_t{4}, py::ssize_t{4}});
  float* data = out.mutable_data();
  // Rotations are copied: forward_kinematics reads them through a mutable LocalPose view.
  std::vector<float> t(translations.data(), translations.data() + translations.size());
  std::vector<float> r(rotations.data(), rotations.data() + rotations.size());
  std::vector<float> s;
  if (scales) s.assign(scales->data(), scales->data() + scales->size());
  std::vector<float> world(static_cast<size_t>(joints) * 16);
  call_released([&] {
    for (py::ssize_t f = 0; f < frames; ++f) {
      const size_t offset = static_cast<size_t>(f * joints);
      LocalPose pose{t.data() + 3 * offset, r.data() + 4 * offset, s.empty() ? nullptr : s.data() + 3 * offset,
                     static_cast<size_t>(joints)};
      const Status status = forward_kinematics(parents.data(), pose, world.data());
      if (!status) return Status::error("frame " + std::to_string(f) + ": " + status.message);
      transpose_matrices(world.data(), static_cast<size_t>(joints), data + 16 * offset);
    }
    return Status::success();
  });
  return out;
}

py::array_t<double> clip_forward_kinematics_py(const py::object& parent_indices, const DoubleArray& translations,
                                               const DoubleArray& rotations) {
  const IndexArray parents = pose_parents(parent_indices, translations, rotations);
  const py::ssize_t joints = parents.shape(0), frames = translations.shape(0);
  py::array_t<double> out({frames, joints, py::ssize_t{4}, py::ssize_t{4}});
  call_released([&] {
    return clip_forward_kinematics(parents.data(), static_cast<size_t>(joints), translations.data(),
                                   rotations.data(), static_cast<size_t>(frames), out.mutable_data());
  });
  return out;
}

py::array_t<double> quaternions_from_matrices_py(const DoubleArray& matrices) {
  require_shape(matrices, "matrices", {-1, 3, 3}, "(N, 3, 3)");
  py::array_t<double> out({matrices.shape(0), py::ssize_t{4}});
  {
    py::gil_scoped_release release;
    quaternions_from_matrices(matrices.data(), static_cast<size_t>(matrices.shape(0)), out.mutable_data());
  }
  return out;
}

py::array_t<float> skin_palette_py(const FloatArray& world, const FloatArray& inverse_bind,
                                   const std::optional<py::object>& joint_node_indices) {
  require_shape(world, "world", {-1, -1, 4, 4}, "(T, J, 4, 4)");
  require_shape(inverse_bind, "inverse_bind", {-1, 4, 4}, "(S, 4, 4)");
  const py::ssize_t frames = world.shape(0), joints = world.shape(1), skin = inverse_bind.shape(0);
  IndexArray nodes;
  if (joint_node_indices) {
    nodes = index_array(as_array(*joint_node_indices, "joint_nodes"), "joint_nodes");
    require_shape(nodes, "joint_nodes", {skin}, "(S,) like inverse_bind");
    for (py::ssize_t i = 0; i < skin; ++i)
      if (nodes.data()[i] < 0 || nodes.data()[i] >= joints)
        throw py::value_error("joint_nodes: skin joint " + std::to_string(i) + " follows node " +
                              std::to_string(nodes.data()[i]) + ", outside [0, " + std::to_string(joints) + ")");
  } else if (skin != joints) {
    throw py::value_error("inverse_bind: " + std::to_string(skin) + " matrices for " + std::to_string(joints) +
                          " joints; pass joint_nodes to skin a subset");
  }
  std::vector<float> world_cm(static_cast<size_t>(frames * joints) * 16), bind_cm(static_cast<size_t>(skin) * 16),
      palette(static_cast<size_t>(skin) * 16);
  transpose_matrices(world.data(), static_cast<size_t>(frames * joints), world_cm.data());
  transpose_matrices(inverse_bind.data(), static_cast<size_t>(skin), bind_cm.data());
  py::array_t<float> out({frames, skin, py::ssize_t{4}, py::ssize_t{4}});
  float* data = out.mutable_data();
  const int32_t* node_data = joint_node_indices ? nodes.data() : nullptr;
  {
    py::gil_scoped_release release;
    for (py::ssize_t f = 0; f < frames; ++f) {
      skin_palette(world_cm.data() + 16 * f * joints, node_data, bind_cm.data(), static_cast<size_t>(skin), palette.data());
      transpose_matrices(palette.data(), static_cast<size_t>(skin), data + 16 * f * skin);
    }
  }
  return out;
}

}  // namespace

void bind_pose(py::module_& m) {
  m.def("sample_keyframes", &sample_keyframes_py, py::arg("times"), py::arg("values"), py::arg("interpolation"),
        py::arg("at"), py::arg("rotation") = false, py::arg("blend") = "slerp",
        R"doc(Samples one glTF animation sampler at the times `at` (glTF 2.0, Appendix C).

Parameters
----------
times : (N,) float32 key times in seconds, strictly increasing.
values : (N, C) float32, or (N, 3, C) for CUBICSPLINE (in-tangent, value, out-tangent).
interpolation : "LINEAR", "STEP" or "CUBICSPLINE".
at : (T,) float32 sample times; the end keys hold outside the keys.
rotation : True for (x, y, z, w) quaternions (C = 4): shortest-arc blend, unit results.
blend : "slerp" (glTF) or "nlerp" for LINEAR rotations.

Returns
-------
(T, C) float32, a new array. ValueError naming the key on unsorted times, non-finite values or a
zero quaternion. The GIL is released while sampling.)doc");

  m.def("forward_kinematics", &forward_kinematics_py, py::arg("parents"), py::arg("translations"),
        py::arg("rotations"), py::arg("scales") = py::none(),
        R"doc(World transforms of every joint in every frame: world[j] = world[parents[j]] @ T @ R @ S.

Parameters
----------
parents : (J,) int32 or int64, -1 or a joint before j (topological order).
translations : (T, J, 3) float32 local translations (the root's is its world position).
rotations : (T, J, 4) float32 local rotations (x, y, z, w); normalised on the way.
scales : (T, J, 3) float32 local scales, or None for unit scale.

Returns
-------
(T, J, 4, 4) float32 in numpy's layout (acting on column vectors), a new array. ValueError
naming the joint (and the frame) on a bad parent or a zero-length rotation.)doc");

  m.def("clip_forward_kinematics", &clip_forward_kinematics_py, py::arg("parents"), py::arg("translations"),
        py::arg("rotations"),
        R"doc(World transforms of every joint in every frame, in double precision (motion processing).

world[t, j] = world[t, parents[j]] @ T(translation) @ R(rotation).

Parameters
----------
parents : (J,) int32 or int64, -1 or a joint before j (topological order).
translations : (T, J, 3) float64 local translations (the root's is its world position).
rotations : (T, J, 4) float64 unit local rotations (x, y, z, w), used as given.

Returns
-------
(T, J, 4, 4) float64 in numpy's layout (acting on column vectors), a new array. ValueError
naming the joint on a bad parent, or the frame and the joint on a non-finite value.)doc");

  m.def("quaternions_from_matrices", &quaternions_from_matrices_py, py::arg("matrices"),
        R"doc(Unit quaternions (x, y, z, w), w >= 0, of rotation matrices (Shepperd's method).

Parameters
----------
matrices : (N, 3, 3) float64 rotation matrices acting on column vectors.

Returns
-------
(N, 4) float64, a new array.)doc");

  m.def("skin_palette", &skin_palette_py, py::arg("world"), py::arg("inverse_bind"), py::arg("joint_nodes") = py::none(),
        R"doc(Skinning palette world[joint_nodes[s]] @ inverse_bind[s] for every frame.

Parameters
----------
world : (T, J, 4, 4) float32 world transforms (numpy layout), e.g. from forward_kinematics.
inverse_bind : (S, 4, 4) float32 inverse bind matrices (numpy layout).
joint_nodes : (S,) int32 or int64 index into J of the node each skin joint follows, or None
    when S == J and skin joint s follows joint s.

Returns
-------
(T, S, 4, 4) float32 (numpy layout), a new array; transpose the last two axes for the
column-major palette a GPU takes.)doc");
}

}  // namespace animlod::bindings
