#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/motion_features.hpp"
#include "array_checks.hpp"
#include "numpy_from_vector.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

py::dict motion_features_py(const FloatArray& frames, const py::array& face_indices,
                            const MotionFeatureOptions& options) {
  require_shape(frames, "frames", {-1, -1, 3}, "(F, V, 3)");
  const IndexArray faces = index_array(face_indices, "faces");
  require_shape(faces, "faces", {-1, 3}, "(M, 3)");
  const AnimatedMeshView mesh{frames.data(), faces.data(), static_cast<size_t>(frames.shape(0)),
                              static_cast<size_t>(frames.shape(1)), static_cast<size_t>(faces.shape(0))};
  MotionFeatures features;
  call_released([&] { return compute_motion_features(mesh, options, features); });
  const auto edge_count = static_cast<py::ssize_t>(features.angle_change.size());
  const auto vertex_count = static_cast<py::ssize_t>(features.vertex_weights.size());
  const auto feature_count = static_cast<py::ssize_t>(features.feature_sizes.size());
  py::dict out;
  out["edges"] = numpy_from_vector(std::move(features.edges), {edge_count, 2});
  out["angle_change"] = numpy_from_vector(std::move(features.angle_change), {edge_count});
  out["connected"] = numpy_from_vector(std::move(features.connected), {edge_count}).attr("view")("bool");
  out["threshold"] = features.threshold;
  out["vertex_feature"] = numpy_from_vector(std::move(features.vertex_feature), {vertex_count});
  out["feature_sizes"] = numpy_from_vector(std::move(features.feature_sizes), {feature_count});
  out["vertex_weights"] = numpy_from_vector(std::move(features.vertex_weights), {vertex_count});
  out["amplitude"] = numpy_from_vector(std::move(features.amplitude), {edge_count});
  return out;
}
}  // namespace

void bind_motion_features(py::module_& m) {
  m.def("motion_features", &motion_features_py, py::arg("frames"), py::arg("faces"),
        py::arg("options") = MotionFeatureOptions{},
        R"doc(Motion features of a deforming mesh (Yang et al. 2019): regions whose dihedral angles change.

Parameters
----------
frames : (F, V, 3) float32 positions per frame (float64 is converted).
faces : (M, 3) int32 or int64 triangles (values must fit int32).
options : MotionFeatureOptions: the threshold (adaptive when 0), the 1-degree floor, boundary
    edges, and the weighting: "amplitude" (default, a vertex weighs 1 + (max_feature_weight - 1) *
    clamp((a - T) / T, 0, 1), a its largest edge amplitude, T the threshold, 1 outside features)
    or "paper" (Eq. 6 as published: every vertex of a feature of w vertices weighs w).

Returns
-------
dict of arrays that own their memory (moved from the core, no copy):
edges (E, 2) int32, angle_change (E,) float32 radians, connected (E,) bool, threshold float,
vertex_feature (V,) int32 (-1 outside features), feature_sizes (C,) int32,
vertex_weights (V,) float32 (Eq. 6 weights of the chosen weighting), amplitude (E,) float32
radians (0 on boundary edges).

Raises ValueError naming the element on a non-finite position, an index out of range, a
degenerate, duplicate or non-manifold face, an unreferenced vertex or a max_feature_weight
below 1. The GIL is released.)doc");
}

}  // namespace animlod::bindings
