#include <optional>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "animlod/ffd_lattice.hpp"
#include "array_checks.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

LatticeBox box_from(const DoubleArray& box) {
  require_shape(box, "box", {4, 3}, "(4, 3): origin, then the S, T, U edge vectors");
  LatticeBox out;
  const double* values = box.data();
  for (int d = 0; d < 3; ++d) out.origin[d] = values[d];
  for (int a = 0; a < 3; ++a)
    for (int d = 0; d < 3; ++d) out.axes[a][d] = values[3 + 3 * a + d];
  return out;
}

// Weights of a lattice of `count` controls, shaped like the lattice or flat.
const double* weights_of(const std::optional<DoubleArray>& weights, py::ssize_t count) {
  if (!weights) return nullptr;
  if (weights->size() != count)
    throw py::value_error("weights: expected " + std::to_string(count) + " values (one per control point), got shape " +
                          shape_string(*weights));
  return weights->data();
}

py::array_t<float> ffd_local_coordinates_py(const FloatArray& points, const DoubleArray& box) {
  require_shape(points, "points", {-1, 3}, "(V, 3)");
  const LatticeBox lattice_box = box_from(box);
  py::array_t<float> out({points.shape(0), py::ssize_t{3}});
  float* out_data = out.mutable_data();
  call_released([&] {
    return ffd_local_coordinates(lattice_box, points.data(), static_cast<size_t>(points.shape(0)), out_data);
  });
  return out;
}

py::array_t<float> ffd_evaluate_py(const FloatArray& local, const DoubleArray& control_points,
                                   const std::optional<DoubleArray>& weights) {
  require_shape(local, "local", {-1, 3}, "(V, 3)");
  require_shape(control_points, "control_points", {-1, -1, -1, 3}, "(l, m, n, 3)");
  LatticeView lattice;
  for (int a = 0; a < 3; ++a) lattice.size[a] = static_cast<size_t>(control_points.shape(a));
  lattice.control_points = control_points.data();
  lattice.weights = weights_of(weights, control_points.size() / 3);
  py::array_t<float> out({local.shape(0), py::ssize_t{3}});
  float* out_data = out.mutable_data();
  call_released([&] { return ffd_evaluate(lattice, local.data(), static_cast<size_t>(local.shape(0)), out_data); });
  return out;
}

py::array_t<float> ffd_displace_py(const FloatArray& rest, const FloatArray& local, const py::array& vertex_lattice_in,
                                   const py::array& sizes_in, const DoubleArray& displacements,
                                   const std::optional<DoubleArray>& weights) {
  require_shape(rest, "rest", {-1, 3}, "(V, 3)");
  const py::ssize_t vertex_count = rest.shape(0);
  require_shape(local, "local", {vertex_count, 3}, "(V, 3) like rest");
  const IndexArray vertex_lattice = index_array(vertex_lattice_in, "vertex_lattice");
  require_shape(vertex_lattice, "vertex_lattice", {vertex_count}, "(V,)");
  const IndexArray sizes = index_array(sizes_in, "sizes");
  require_shape(sizes, "sizes", {-1, 3}, "(R, 3)");
  const bool single = displacements.ndim() == 2;
  if (single) require_shape(displacements, "displacements", {-1, 3}, "(C, 3) or (F, C, 3)");
  else require_shape(displacements, "displacements", {-1, -1, 3}, "(C, 3) or (F, C, 3)");
  const py::ssize_t frames = single ? 1 : displacements.shape(0);
  const py::ssize_t controls = displacements.shape(single ? 0 : 1);
  py::ssize_t expected = 0;
  for (py::ssize_t r = 0; r < sizes.shape(0); ++r)
    expected += static_cast<py::ssize_t>(sizes.at(r, 0)) * sizes.at(r, 1) * sizes.at(r, 2);
  if (controls != expected)
    throw py::value_error("displacements: " + std::to_string(controls) + " control points, the lattice sizes give " +
                          std::to_string(expected));
  LatticeSetView set;
  set.lattice_count = static_cast<size_t>(sizes.shape(0));
  set.sizes = sizes.data();
  set.displacements = displacements.data();
  set.weights = weights_of(weights, controls);
  set.frame_count = static_cast<size_t>(frames);
  py::array_t<float> out = single ? py::array_t<float>({vertex_count, py::ssize_t{3}})
                                  : py::array_t<float>({frames, vertex_count, py::ssize_t{3}});
  float* out_data = out.mutable_data();
  call_released([&] {
    return ffd_displace(set, rest.data(), local.data(), vertex_lattice.data(), static_cast<size_t>(vertex_count),
                        out_data);
  });
  return out;
}

py::array_t<double> ffd_fit_py(const FloatArray& local, const FloatArray& targets, const std::vector<size_t>& size,
                               const std::optional<DoubleArray>& weights, const std::optional<DoubleArray>& prior,
                               const FfdFitOptions& options) {
  require_shape(local, "local", {-1, 3}, "(V, 3)");
  require_shape(targets, "targets", {local.shape(0), 3}, "(V, 3) like local");
  if (size.size() != 3) throw py::value_error("size: expected 3 control-point counts (l, m, n)");
  const size_t lattice_size[3] = {size[0], size[1], size[2]};
  const py::ssize_t count = static_cast<py::ssize_t>(size[0] * size[1] * size[2]);
  const double* weight_data = weights_of(weights, count);
  if (prior && prior->size() != 3 * count)
    throw py::value_error("prior: expected " + std::to_string(count) + " control points (l, m, n, 3), got shape " +
                          shape_string(*prior));
  const double* prior_data = prior ? prior->data() : nullptr;
  py::array_t<double> out({static_cast<py::ssize_t>(size[0]), static_cast<py::ssize_t>(size[1]),
                           static_cast<py::ssize_t>(size[2]), py::ssize_t{3}});
  double* out_data = out.mutable_data();
  call_released([&] {
    return ffd_fit(lattice_size, weight_data, local.data(), targets.data(), static_cast<size_t>(local.shape(0)),
                   prior_data, out_data, options);
  });
  return out;
}
}  // namespace

void bind_ffd_lattice(py::module_& m) {
  m.def("ffd_local_coordinates", &ffd_local_coordinates_py, py::arg("points"), py::arg("box"),
        R"doc(Local coordinates (s, t, u) of points in a lattice box: p = origin + s S + t T + u U.

Parameters
----------
points : (V, 3) float32 positions, asset units (float64 is converted).
box : (4, 3) float64, the origin and the S, T, U edge vectors.

Returns
-------
(V, 3) float32, a new array (not clamped; outside [0, 1] is outside the box).

Raises ValueError naming the axis of a degenerate box (zero, or in the plane of the other two)
or a non-finite point. The GIL is released.)doc");
  m.def("ffd_evaluate", &ffd_evaluate_py, py::arg("local"), py::arg("control_points"), py::arg("weights") = py::none(),
        R"doc(Rational Bezier volume of a lattice at local coordinates (rational FFD).

X(s,t,u) = sum w_ijk B_i(s) B_j(t) B_k(u) P_ijk / sum w_ijk B_i(s) B_j(t) B_k(u), Bernstein
degree = size - 1 per axis; weights None (all ones) is the plain Bezier FFD.

Parameters
----------
local : (V, 3) float32 local coordinates, clamped to [0, 1].
control_points : (l, m, n, 3) float64, each size in [2, 16].
weights : (l, m, n) float64 > 0, or None.

Returns
-------
(V, 3) float32, a new array. Raises ValueError on a bad size or weight (naming the control
point) or a non-finite coordinate (naming the point). The GIL is released.)doc");
  m.def("ffd_displace", &ffd_displace_py, py::arg("rest"), py::arg("local"), py::arg("vertex_lattice"),
        py::arg("sizes"), py::arg("displacements"), py::arg("weights") = py::none(),
        R"doc(Deform vertices by the rational FFD of their lattice's control-point displacements.

out[f, v] = rest[v] + X_delta(local[v]) with lattice vertex_lattice[v] and frame f's
displacements; vertices with vertex_lattice -1 stay at rest.

Parameters
----------
rest : (V, 3) float32 positions.
local : (V, 3) float32 local coordinates of each vertex in its lattice's box (clamped to [0, 1]).
vertex_lattice : (V,) int32 lattice of each vertex, or -1.
sizes : (R, 3) int32 control points per axis of each lattice, each in [2, 16].
displacements : (C, 3) or (F, C, 3) float64, C = sum of l m n, lattices in order.
weights : (C,) float64 > 0, or None for all ones.

Returns
-------
(V, 3) or (F, V, 3) float32 (as displacements has one frame or F), a new array. Raises
ValueError on wrong shapes, bad sizes or weights, or a vertex_lattice entry out of range (naming
the vertex). The GIL is released.)doc");
  m.def("ffd_fit", &ffd_fit_py, py::arg("local"), py::arg("targets"), py::arg("size"), py::arg("weights") = py::none(),
        py::kw_only(), py::arg("prior") = py::none(), py::arg("options") = FfdFitOptions{},
        R"doc(Least-squares lattice: control points P minimising sum_v |X_P(local[v]) - targets[v]|^2,
plus, on the correction Q = P - prior, options.smoothness * (V / C) * the squared second differences of Q
along the lattice lines and options.ridge * (V / C) * |Q|^2 (C control points), so that control points
the points hardly determine stay at the prior.

Parameters
----------
local : (V, 3) float32 local coordinates (clamped to [0, 1]).
targets : (V, 3) float32 positions (or displacements) to reproduce.
size : (l, m, n), each in [2, 16] (e.g. (2, 2, 2) to replace a 3x3x3 lattice).
weights : (l, m, n) float64 > 0, or None.
prior : (l, m, n, 3) float64, or None for zeros.
options : FfdFitOptions, the regularisation weights smoothness and ridge, >= 0 (0 and 0: plain
    least squares, least norm where the points leave control points free).

Returns
-------
(l, m, n, 3) float64, a new array. Raises ValueError on no points, a bad size, weight or
regularisation weight, or a non-finite input (naming the point).
The GIL is released.)doc");
}

}  // namespace animlod::bindings
