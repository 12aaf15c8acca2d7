#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/point_mesh_distance.hpp"
#include "array_checks.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// The points' and the mesh's shapes checked ((N, 3) and (V, 3), or (T, N, 3) and (T, V, 3)); the
// mesh viewed over `vertices` and `faces`, which must outlive the view.
TriangleMeshView checked_mesh(const DoubleArray& points, const DoubleArray& vertices, const IndexArray& faces) {
  const bool frames = points.ndim() == 3;
  if (frames) {
    require_shape(points, "points", {-1, -1, 3}, "(T, N, 3)");
    require_shape(vertices, "vertices", {points.shape(0), -1, 3}, "(T, V, 3) with the points' T");
  } else {
    require_shape(points, "points", {-1, 3}, "(N, 3)");
    require_shape(vertices, "vertices", {-1, 3}, "(V, 3)");
  }
  require_shape(faces, "faces", {-1, 3}, "(F, 3)");
  TriangleMeshView mesh;
  mesh.vertices = vertices.data();
  mesh.vertex_count = static_cast<size_t>(vertices.shape(frames ? 1 : 0));
  mesh.faces = faces.data();
  mesh.face_count = static_cast<size_t>(faces.shape(0));
  mesh.frame_count = frames ? static_cast<size_t>(points.shape(0)) : 1;
  return mesh;
}

size_t point_count_of(const DoubleArray& points) { return static_cast<size_t>(points.shape(points.ndim() - 2)); }

py::array_t<double> point_mesh_squared_distance_py(const DoubleArray& points, const DoubleArray& vertices,
                                                   const py::array& face_indices, unsigned threads) {
  const IndexArray faces = index_array(face_indices, "faces");
  const TriangleMeshView mesh = checked_mesh(points, vertices, faces);
  py::array_t<double> out = points.ndim() == 3 ? py::array_t<double>({points.shape(0), points.shape(1)})
                                               : py::array_t<double>(points.shape(0));
  double* out_data = out.mutable_data();
  call_released([&] {
    return point_mesh_squared_distance(mesh, points.data(), point_count_of(points), threads, out_data);
  });
  return out;
}

double point_mesh_max_squared_distance_py(const DoubleArray& points, const DoubleArray& vertices,
                                          const py::array& face_indices, double floor, unsigned threads) {
  const IndexArray faces = index_array(face_indices, "faces");
  const TriangleMeshView mesh = checked_mesh(points, vertices, faces);
  double out = floor;
  call_released([&] {
    return point_mesh_max_squared_distance(mesh, points.data(), point_count_of(points), threads, floor, out);
  });
  return out;
}

py::array_t<double> point_mesh_max_squared_distances_py(const DoubleArray& points, const DoubleArray& vertices,
                                                        const py::array& face_indices, const py::array& segment_ends,
                                                        const DoubleArray& floors, unsigned threads) {
  const IndexArray faces = index_array(face_indices, "faces");
  const IndexArray ends = index_array(segment_ends, "segment_ends");
  require_shape(ends, "segment_ends", {-1}, "(S,)");
  require_shape(floors, "floors", {ends.shape(0)}, "(S,) like segment_ends");
  const TriangleMeshView mesh = checked_mesh(points, vertices, faces);
  std::vector<size_t> checked_ends;
  for (py::ssize_t s = 0; s < ends.shape(0); ++s) {
    if (ends.data()[s] < 0) throw py::value_error("segment_ends[" + std::to_string(s) + "]: negative");
    checked_ends.push_back(static_cast<size_t>(ends.data()[s]));
  }
  py::array_t<double> out(ends.shape(0));
  double* out_data = out.mutable_data();
  call_released([&] {
    return point_mesh_max_squared_distances(mesh, points.data(), point_count_of(points), checked_ends.data(),
                                            checked_ends.size(), threads, floors.data(), out_data);
  });
  return out;
}

py::array_t<double> point_mesh_frame_max_squared_distances_py(const DoubleArray& points, const DoubleArray& vertices,
                                                              const py::array& face_indices, unsigned threads) {
  const IndexArray faces = index_array(face_indices, "faces");
  require_shape(points, "points", {-1, -1, 3}, "(T, N, 3)");
  const TriangleMeshView mesh = checked_mesh(points, vertices, faces);
  py::array_t<double> out(points.shape(0));
  double* out_data = out.mutable_data();
  call_released([&] {
    return point_mesh_frame_max_squared_distances(mesh, points.data(), point_count_of(points), threads, out_data);
  });
  return out;
}

}  // namespace

void bind_point_mesh_distance(py::module_& m) {
  m.def("point_mesh_squared_distance", &point_mesh_squared_distance_py, py::arg("points"), py::arg("vertices"),
        py::arg("faces"), py::arg("threads") = 0,
        R"doc(Squared distance from each point to the nearest point of a triangle mesh.

Parameters
----------
points : (N, 3) float64 query points (other float dtypes are converted), or (T, N, 3): the
    points of T frames, each measured against the mesh in its frame.
vertices : (V, 3) float64 mesh vertices, or (T, V, 3) with the points' T.
faces : (F, 3) int32 or int64 vertex indices, F >= 1, shared by every frame.
threads : threads to query on (0: :func:`thread_limit`); the result does not depend on it.

Returns
-------
(N,) or (T, N) float64. Degenerate triangles count as their edges. Frames after the first reuse
its tree with refitted boxes.

Raises ValueError on a wrong shape, no face, a face index outside [0, V) or a non-finite
vertex or point. The GIL is released while measuring.)doc");
  m.def("point_mesh_max_squared_distance", &point_mesh_max_squared_distance_py, py::arg("points"),
        py::arg("vertices"), py::arg("faces"), py::arg("floor") = 0.0, py::arg("threads") = 0,
        R"doc(The largest squared distance from the points to a triangle mesh, over every point and frame.

The same arguments as :func:`point_mesh_squared_distance`, and ``floor``: a running maximum the
caller holds. Returns ``max(floor, point_mesh_squared_distance(points, vertices, faces).max())``
to the bit, for any thread count, at a fraction of the cost: a point's search ends at the first
triangle no farther than the largest distance found so far (or ``floor``), since such a point
cannot raise it (a one-sided Hausdorff distance with an early break). The same errors, and a
NaN floor.)doc");
  m.def("point_mesh_max_squared_distances", &point_mesh_max_squared_distances_py, py::arg("points"),
        py::arg("vertices"), py::arg("faces"), py::arg("segment_ends"), py::arg("floors"), py::arg("threads") = 0,
        R"doc(:func:`point_mesh_max_squared_distance` of each segment of the points alone, with one tree.

Segment s is each frame's points ``[segment_ends[s - 1], segment_ends[s])`` (from 0; the last
end is N) with its own ``floors[s]``: several levels' points measured against one mesh, whose
tree is built once and refitted once per frame. Returns (S,) float64, each equal to the
single-segment call on its points to the bit. The same errors, and segment ends that decrease or
do not end at N.)doc");
  m.def("point_mesh_frame_max_squared_distances", &point_mesh_frame_max_squared_distances_py, py::arg("points"),
        py::arg("vertices"), py::arg("faces"), py::arg("threads") = 0,
        R"doc(The largest squared distance from the points to a triangle mesh in each frame alone.

The arguments of :func:`point_mesh_squared_distance` with (T, N, 3) points. Returns (T,) float64,
``point_mesh_squared_distance(points, vertices, faces).max(axis=1)`` to the bit (0 for a frame
of no point), for any thread count, at the cost of :func:`point_mesh_max_squared_distance`: a
point's search ends at the first triangle no farther than its frame's largest so far. The same
errors.)doc");
}

}  // namespace animlod::bindings
