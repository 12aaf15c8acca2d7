#include <optional>
#include <string>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "animlod/aqem.hpp"
#include "array_checks.hpp"
#include "numpy_from_vector.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

py::dict level_to_dict(AqemLevel&& level, py::ssize_t frame_count, py::ssize_t attribute_count,
                       py::ssize_t influence_count, py::ssize_t position_attribute_count) {
  const auto kept = static_cast<py::ssize_t>(level.kept_vertices.size());
  const auto face_count = static_cast<py::ssize_t>(level.faces.size() / 3);
  const auto vertex_count = static_cast<py::ssize_t>(level.vertex_map.size());
  py::dict out;
  out["target_face_count"] = level.target_face_count;
  out["reached"] = level.reached;
  out["stopped_by_max_error"] = level.stopped_by_max_error;
  out["collapse_count"] = level.collapse_count;
  out["error"] = level.error;
  out["faces"] = numpy_from_vector(std::move(level.faces), {face_count, 3});
  out["face_sources"] = numpy_from_vector(std::move(level.face_sources), {face_count});
  out["kept_vertices"] = numpy_from_vector(std::move(level.kept_vertices), {kept});
  out["vertex_map"] = numpy_from_vector(std::move(level.vertex_map), {vertex_count});
  out["positions"] = numpy_from_vector(std::move(level.positions), {frame_count, kept, 3});
  out["attributes"] = numpy_from_vector(std::move(level.attributes), {kept, attribute_count});
  out["skin_joints"] = numpy_from_vector(std::move(level.skin_joints), {level.skin_joints.empty() ? 0 : kept, influence_count});
  out["skin_weights"] = numpy_from_vector(std::move(level.skin_weights), {level.skin_weights.empty() ? 0 : kept, influence_count});
  out["position_attributes"] =
      numpy_from_vector(std::move(level.position_attributes), {kept, position_attribute_count});
  return out;
}

py::dict simplify_animated_py(const FloatArray& frames, const py::array& face_indices, AqemOptions options,
                              const std::optional<MaskArray>& locked, const std::optional<MaskArray>& guarded,
                              const std::optional<FloatArray>& importance, const std::optional<FloatArray>& attributes,
                              const std::optional<FloatArray>& position_attributes,
                              const std::optional<py::array>& skin_joint_indices,
                              const std::optional<FloatArray>& skin_weights,
                              const std::optional<py::array>& face_group_indices,
                              const std::optional<py::function>& progress) {
  require_shape(frames, "frames", {-1, -1, 3}, "(F, V, 3)");
  const IndexArray faces = index_array(face_indices, "faces");
  require_shape(faces, "faces", {-1, 3}, "(M, 3)");
  const py::ssize_t vertex_count = frames.shape(1);
  const AnimatedMeshView mesh{frames.data(), faces.data(), static_cast<size_t>(frames.shape(0)),
                              static_cast<size_t>(vertex_count), static_cast<size_t>(faces.shape(0))};

  AqemVertexData data;
  if (locked) {
    require_shape(*locked, "locked", {vertex_count}, "(V,)");
    data.locked = locked->data();
  }
  if (guarded) {
    require_shape(*guarded, "guarded", {vertex_count}, "(V,)");
    data.guarded = guarded->data();
  }
  if (importance) {
    require_shape(*importance, "importance", {vertex_count}, "(V,)");
    data.importance = importance->data();
  }
  if (attributes) {
    require_shape(*attributes, "attributes", {vertex_count, -1}, "(V, A)");
    data.attributes = attributes->data();
    data.attribute_count = static_cast<size_t>(attributes->shape(1));
  }
  if (position_attributes) {
    require_shape(*position_attributes, "position_attributes", {vertex_count, -1}, "(V, B)");
    data.position_attributes = position_attributes->data();
    data.position_attribute_count = static_cast<size_t>(position_attributes->shape(1));
  }
  std::optional<IndexArray> face_groups;
  if (face_group_indices) {
    face_groups = index_array(*face_group_indices, "face_groups");
    require_shape(*face_groups, "face_groups", {faces.shape(0)}, "(M,)");
    data.face_groups = face_groups->data();
  }
  std::optional<IndexArray> skin_joints;
  if (skin_joint_indices) skin_joints = index_array(*skin_joint_indices, "skin_joints");
  if (skin_joints.has_value() != skin_weights.has_value())
    throw py::value_error("skin_joints and skin_weights: give both or neither");
  if (skin_joints) {
    require_shape(*skin_joints, "skin_joints", {vertex_count, -1}, "(V, K)");
    require_shape(*skin_weights, "skin_weights", {vertex_count, skin_joints->shape(1)}, "(V, K) like skin_joints");
    data.skin_joints = skin_joints->data();
    data.skin_weights = skin_weights->data();
    data.influence_count = static_cast<size_t>(skin_joints->shape(1));
  }

  options.progress = progress_callback(progress);

  AqemResult result;
  call_released([&] { return simplify_animated(mesh, data, options, result); });

  const py::ssize_t frame_count = frames.shape(0);
  py::list levels;
  for (AqemLevel& level : result.levels)
    levels.append(level_to_dict(std::move(level), frame_count, static_cast<py::ssize_t>(data.attribute_count),
                                static_cast<py::ssize_t>(data.influence_count),
                                static_cast<py::ssize_t>(data.position_attribute_count)));
  CollapseRecord& record = result.collapses;
  const auto collapse_count = static_cast<py::ssize_t>(record.removed.size());
  py::dict collapses;
  collapses["removed"] = numpy_from_vector(std::move(record.removed), {collapse_count});
  collapses["kept"] = numpy_from_vector(std::move(record.kept), {collapse_count});
  const size_t recorded = record.positions.empty() ? 0 : collapse_count;
  collapses["positions"] = numpy_from_vector(std::move(record.positions), {recorded, frame_count, 3});
  collapses["cost"] = numpy_from_vector(std::move(record.cost), {collapse_count});
  collapses["error"] = numpy_from_vector(std::move(record.error), {collapse_count});
  py::dict out;
  out["levels"] = levels;
  out["collapses"] = collapses;
  const auto used = static_cast<py::ssize_t>(result.frames_used.size());
  out["frames_used"] = numpy_from_vector(std::move(result.frames_used), {used});
  out["vertex_weights"] = numpy_from_vector(std::move(result.vertex_weights), {vertex_count});
  const AqemPreparation& report = result.preparation;
  py::dict preparation;
  preparation["degenerate_faces"] = report.degenerate_faces;
  preparation["duplicate_faces"] = report.duplicate_faces;
  preparation["mirrored_faces"] = report.mirrored_faces;
  preparation["welded_vertices"] = report.welded_vertices;
  preparation["seam_vertices"] = report.seam_vertices;
  preparation["split_vertices"] = report.split_vertices;
  preparation["unreferenced_vertices"] = report.unreferenced_vertices;
  preparation["face_count"] = report.face_count;
  out["preparation"] = preparation;
  const AqemTimings& timings = result.seconds;
  py::dict seconds;
  seconds["preparation"] = timings.preparation;
  seconds["motion_features"] = timings.motion_features;
  seconds["connectivity"] = timings.connectivity;
  seconds["quadrics"] = timings.quadrics;
  seconds["ranking"] = timings.ranking;
  seconds["choosing"] = timings.choosing;
  seconds["collapsing"] = timings.collapsing;
  seconds["levels"] = timings.levels;
  out["seconds"] = seconds;
  return out;
}
}  // namespace

void bind_aqem(py::module_& m) {
  m.def(
      "check_aqem_options", [](const AqemOptions& options) { raise_if_error(check_aqem_options(options)); },
      py::arg("options"),
      R"doc(Raises ValueError naming the option when ``options`` hold a value simplify_animated
refuses whatever the mesh (no level, a ratio outside (0, 1], a face count of 0, a negative
max_error, a negative frame, a motion-feature option out of range). Face counts above a mesh's
face count and frames past its last are refused by simplify_animated alone.)doc");
  m.def("simplify_animated", &simplify_animated_py, py::arg("frames"), py::arg("faces"),
        py::arg("options") = AqemOptions{}, py::kw_only(), py::arg("locked") = py::none(),
        py::arg("guarded") = py::none(), py::arg("importance") = py::none(), py::arg("attributes") = py::none(),
        py::arg("position_attributes") = py::none(), py::arg("skin_joints") = py::none(),
        py::arg("skin_weights") = py::none(), py::arg("face_groups") = py::none(), py::arg("progress") = py::none(),
        R"doc(AQEM simplification of a deforming mesh over all its frames (Yang et al. 2019, Eqs. 1-7).

Parameters
----------
frames : (F, V, 3) float32 positions per frame (float64 is converted).
faces : (M, 3) int32 or int64 triangles (values must fit int32). Any topology: seam copies are
    welded, degenerate and repeated faces dropped, non-manifold spots cut and locked.
options : AqemOptions (the levels, Eq. 6 weights, quadrics, inversion test, placement, weld).
locked : (V,) bool, vertices never removed or moved.  importance : (V,) float32 > 0 weights.
attributes : (V, A) float32 interpolated along collapses (UVs, normals, colours); copies of a
    position with different attributes form a seam that only collapses along itself.
skin_joints, skin_weights : (V, K) int32 or int64 / float32, merged keeping the top K.
progress : callable(done, total) called with the GIL held now and then.
position_attributes : (V, B) float32 that follow the position (morph target deltas): copies weld
    only when they agree; blended once per collapse.
face_groups : (M,) int32 material or primitive per face; group borders are seams.
guarded : (V,) bool, vertices kept in place until no other collapse is legal.

Returns
-------
dict with "levels" (list, finest first, of dicts: faces (M', 3), face_sources (M',),
kept_vertices (V',), vertex_map (V,), positions (F, V', 3), attributes, position_attributes,
skin_joints, skin_weights, error, reached, target_face_count, collapse_count), "collapses"
(removed, kept (C,), positions (C, F, 3), cost, error (C,)), "frames_used", "vertex_weights" (V,)
and "preparation" (counts of degenerate_faces, duplicate_faces, welded_vertices, seam_vertices,
split_vertices, unreferenced_vertices, and face_count simplified), "seconds" (wall-clock seconds
of the phases: preparation, motion_features, connectivity, quadrics, ranking, choosing,
collapsing, levels; see AqemTimings in animlod/aqem.hpp). Arrays own their memory (moved
from the core, no copy). The GIL is released while simplifying.

Raises ValueError naming the element for bad meshes, targets or per-vertex inputs.)doc");
}

}  // namespace animlod::bindings
