#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/point_mesh_distance.hpp"
#include "array_checks.hpp"

namespace animlod::bindings {

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

py::array_t<double> point_mesh_squared_distance_py(const DoubleArray& points, const DoubleArray& vertices,
                                                   const py::array& face_indices, unsigned threads) {
  const bool frames = points.ndim() == 3;
  if (frames) {
    require_shape(points, "points", {-1, -1, 3}, "(T, N, 3)");
    require_shape(vertices, "vertices", {points.shape(0), -1, 3}, "(T, V, 3) with the points' T");
  } else {
    require_shape(points, "points", {-1, 3}, "(N, 3)");
    require_shape(vertices, "vertices", {-1, 3}, "(V, 3)");
  }
  const IndexArray faces = index_array(face_indices, "faces");
  require_shape(faces, "faces", {-1, 3}, "(F, 3)");
  TriangleMeshView mesh;
  mesh.vertices = vertices.data();
  mesh.vertex_count = static_cast<size_t>(vertices.shape(frames ? 1 : 0));
  mesh.faces = faces.data();
  mesh.face_count = static_cast<size_t>(faces.shape(0));
  mesh.frame_count = frames ? static_cast<size_t>(points.shape(0)) : 1;
  const auto point_count = static_cast<size_t>(points.shape(frames ? 1 : 0));
  py::array_t<double> out = frames ? py::array_t<double>({points.shape(0), points.shape(1)})
                                   : py::array_t<double>(points.shape(0));
  double* out_data = out.mutable_data();
  Status status;
  {
    py::gil_scoped_release release;
    status = point_mesh_squared_distance(mesh, points.data(), point_count, threads, out_data);
  }
  raise_if_error(status);
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
threads : threads to query on (0: every core); the result does not depend on it.

Returns
-------
(N,) or (T, N) float64. Degenerate triangles count as their edges. Frames after the first reuse
its tree with refitted boxes.

Raises ValueError on a wrong shape, no face, a face index outside [0, V) or a non-finite
vertex or point. The GIL is released while measuring.)doc");
}

}  // namespace animlod::bindings
