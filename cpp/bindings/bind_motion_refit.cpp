#include <optional>
#include <string>
#include <utility>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "animlod/motion_refit.hpp"
#include "array_checks.hpp"
#include "numpy_from_vector.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

// A MotionRefitProblem that owns its arrays (the core's struct is a view of them).
struct ProblemHolder {
  IndexArray length_pairs, coincident_pairs, handed_quads, angle_triples, flat_quads;
  DoubleArray key_lengths, key_volumes, key_cosines, flat_volumes, flat_areas;
  MotionRefitProblem view;
};

IndexArray rows_of(const py::array& a, const char* name, py::ssize_t width, const char* expected) {
  IndexArray out = index_array(a, name);
  require_shape(out, name, {-1, width}, expected);
  return out;
}

ProblemHolder make_problem(size_t point_count, const py::array& length_pairs, const DoubleArray& key_lengths,
                           const py::array& coincident_pairs, const py::array& handed_quads,
                           const DoubleArray& key_volumes, const py::array& angle_triples,
                           const DoubleArray& key_cosines, double distance_weight, double string_weight,
                           double angle_weight, double length_scale, const py::array& flat_quads,
                           const DoubleArray& flat_volumes, const DoubleArray& flat_areas) {
  ProblemHolder h;
  h.length_pairs = rows_of(length_pairs, "length_pairs", 2, "(Np, 2)");
  h.coincident_pairs = rows_of(coincident_pairs, "coincident_pairs", 2, "(Nc, 2)");
  h.handed_quads = rows_of(handed_quads, "handed_quads", 4, "(Nh, 4)");
  h.angle_triples = rows_of(angle_triples, "angle_triples", 3, "(Na, 3)");
  h.flat_quads = rows_of(flat_quads, "flat_quads", 4, "(Nf, 4)");
  h.key_lengths = key_lengths;
  h.key_volumes = key_volumes;
  h.key_cosines = key_cosines;
  h.flat_volumes = flat_volumes;
  h.flat_areas = flat_areas;
  require_shape(h.key_lengths, "key_lengths", {h.length_pairs.shape(0)}, "(Np,) like length_pairs");
  require_shape(h.key_volumes, "key_volumes", {h.handed_quads.shape(0)}, "(Nh,) like handed_quads");
  require_shape(h.key_cosines, "key_cosines", {h.angle_triples.shape(0)}, "(Na,) like angle_triples");
  require_shape(h.flat_volumes, "flat_volumes", {h.flat_quads.shape(0)}, "(Nf,) like flat_quads");
  require_shape(h.flat_areas, "flat_areas", {h.flat_quads.shape(0)}, "(Nf,) like flat_quads");
  MotionRefitProblem& v = h.view;
  v.point_count = point_count;
  v.length_pairs = h.length_pairs.data();
  v.key_lengths = h.key_lengths.data();
  v.length_pair_count = static_cast<size_t>(h.length_pairs.shape(0));
  v.coincident_pairs = h.coincident_pairs.data();
  v.coincident_pair_count = static_cast<size_t>(h.coincident_pairs.shape(0));
  v.handed_quads = h.handed_quads.data();
  v.key_volumes = h.key_volumes.data();
  v.handed_quad_count = static_cast<size_t>(h.handed_quads.shape(0));
  v.angle_triples = h.angle_triples.data();
  v.key_cosines = h.key_cosines.data();
  v.angle_triple_count = static_cast<size_t>(h.angle_triples.shape(0));
  v.flat_quads = h.flat_quads.data();
  v.flat_volumes = h.flat_volumes.data();
  v.flat_areas = h.flat_areas.data();
  v.flat_quad_count = static_cast<size_t>(h.flat_quads.shape(0));
  v.distance_weight = distance_weight;
  v.string_weight = string_weight;
  v.angle_weight = angle_weight;
  v.length_scale = length_scale;
  raise_if_error(validate_motion_refit_problem(v));
  return h;
}

void require_frames(const DoubleArray& a, const char* name, const ProblemHolder& h) {
  require_shape(a, name, {-1, static_cast<py::ssize_t>(h.view.point_count), 3}, "(F, P, 3)");
}

py::tuple objective_py(const ProblemHolder& h, const DoubleArray& x, const DoubleArray& original) {
  require_frames(x, "x", h);
  require_frames(original, "original", h);
  if (original.shape(0) != x.shape(0))
    throw py::value_error("original: expected shape " + shape_string(x) + " like x, got " + shape_string(original));
  const auto frames = x.shape(0);
  DoubleArray values(frames);
  DoubleArray gradient({frames, static_cast<py::ssize_t>(h.view.point_count), py::ssize_t{3}});
  double* values_out = values.mutable_data();
  double* gradient_out = gradient.mutable_data();
  call_released([&] {
    return motion_refit_objective(h.view, x.data(), original.data(), static_cast<size_t>(frames), values_out,
                                  gradient_out);
  });
  return py::make_tuple(values, gradient);
}

template <typename Function>
py::tuple constraints_py(const ProblemHolder& h, const DoubleArray& x, size_t rows, Function function) {
  require_frames(x, "x", h);
  const auto frames = x.shape(0);
  const auto points = static_cast<py::ssize_t>(h.view.point_count);
  DoubleArray values({frames, static_cast<py::ssize_t>(rows)});
  DoubleArray jacobian({frames, static_cast<py::ssize_t>(rows), points, py::ssize_t{3}});
  double* values_out = values.mutable_data();
  double* jacobian_out = jacobian.mutable_data();
  call_released([&] { return function(h.view, x.data(), static_cast<size_t>(frames), values_out, jacobian_out); });
  return py::make_tuple(values, jacobian);
}

py::dict solve_py(const ProblemHolder& h, const DoubleArray& original, const DoubleArray& fallback,
                  const MotionRefitOptions& options, const std::optional<DoubleArray>& cold_starts) {
  require_frames(original, "original", h);
  for (const auto& [array, name] : {std::pair{&fallback, "fallback"}, std::pair{cold_starts ? &*cold_starts : nullptr,
                                                                               "cold_starts"}}) {
    if (array == nullptr) continue;
    require_frames(*array, name, h);
    if (array->shape(0) != original.shape(0))
      throw py::value_error(std::string(name) + ": expected shape " + shape_string(original) + " like original, got " +
                            shape_string(*array));
  }
  const double* cold = cold_starts ? cold_starts->data() : nullptr;
  MotionRefitResult result;
  call_released([&] {
    return motion_refit_solve(h.view, original.data(), fallback.data(), cold,
                              static_cast<size_t>(original.shape(0)), options, result);
  });
  const auto frames = original.shape(0);
  py::list failures;
  for (const auto& f : result.failures) failures.append(py::make_tuple(f.frame, f.reason, f.fell_back));
  py::dict out;
  out["positions"] = numpy_from_vector(std::move(result.positions),
                                       {frames, static_cast<py::ssize_t>(h.view.point_count), py::ssize_t{3}});
  out["values"] = numpy_from_vector(std::move(result.values), {frames});
  out["evaluations"] = numpy_from_vector(std::move(result.evaluations), {frames});
  out["failures"] = failures;
  return out;
}

}  // namespace

void bind_motion_refit(py::module_& m) {
  py::class_<ProblemHolder>(m, "MotionRefitProblem", R"doc(One motion LoD level's per-frame re-fit problem (Eqs. 4-8).

Built from python/animlod/motion_lod/objective.RefitProblem; holds copies of its arrays (index
arrays as int32, values as float64). P points, point 0 the root.)doc")
      .def(py::init(&make_problem), py::arg("point_count"), py::arg("length_pairs"), py::arg("key_lengths"),
           py::arg("coincident_pairs"), py::arg("handed_quads"), py::arg("key_volumes"), py::arg("angle_triples"),
           py::arg("key_cosines"), py::arg("distance_weight"), py::arg("string_weight"), py::arg("angle_weight"),
           py::arg("length_scale"), py::arg("flat_quads") = py::array_t<int32_t>(std::vector<py::ssize_t>{0, 4}),
           py::arg("flat_volumes") = DoubleArray(0), py::arg("flat_areas") = DoubleArray(0),
           R"doc(length_pairs (Np, 2), key_lengths (Np,), coincident_pairs (Nc, 2), handed_quads (Nh, 4),
key_volumes (Nh,), angle_triples (Na, 3), key_cosines (Na,); weights alpha, beta, gamma of Eq. 5;
length_scale L in the asset's units; flat_quads (Nf, 4), flat_volumes (Nf,), flat_areas (Nf,):
rigid groups held by their child's height over the base plane (none by default). Raises
ValueError naming the array and element on an index outside [0, P), a repeated point, a
non-positive key length or flat area, a zero key volume, a cosine outside [-1, 1], alpha <= 0
or L <= 0.)doc")
      .def_property_readonly("point_count", [](const ProblemHolder& h) { return h.view.point_count; })
      .def_property_readonly("equality_count", [](const ProblemHolder& h) { return motion_refit_equality_count(h.view); });

  const MotionRefitOptions defaults;
  m.def("motion_refit_objective", &objective_py, py::arg("problem"), py::arg("x"), py::arg("original"),
        R"doc(E (Eq. 5) per frame and its gradient.

x, original : (F, P, 3) float64 candidate and original positions (x's root row is ignored).
Returns (values (F,), gradient (F, P, 3)), new float64 arrays (root gradient 0). GIL released.)doc");
  m.def(
      "motion_refit_equalities",
      [](const ProblemHolder& h, const DoubleArray& x) {
        return constraints_py(h, x, motion_refit_equality_count(h.view), motion_refit_equalities);
      },
      py::arg("problem"), py::arg("x"),
      R"doc(The hard equalities scaled by 1/L and their Jacobian.

x : (F, P, 3) float64. Returns (values (F, m), jacobian (F, m, P, 3)), m = Np + 3 Nc: one row
per held length, (|x_a - x_b| - b0) / L, then three per coincident pair, (x_a - x_b) / L.)doc");
  m.def(
      "motion_refit_handedness",
      [](const ProblemHolder& h, const DoubleArray& x) {
        return constraints_py(h, x, h.view.handed_quad_count, motion_refit_handedness);
      },
      py::arg("problem"), py::arg("x"),
      R"doc(The handedness inequalities (<= 0 when kept) and their Jacobian.

x : (F, P, 3) float64. Returns (values (F, Nh), jacobian (F, Nh, P, 3)):
-sign(V0) det[a - p, b - p, c - p] / L^3 per handed quad.)doc");
  m.def("motion_refit_solve", &solve_py, py::arg("problem"), py::arg("original"), py::arg("fallback"),
        py::arg("options") = defaults, py::arg("cold_starts") = py::none(),
        R"doc(Re-fit every frame with nlopt's SLSQP, chunks of frames on several threads.

original : (T, P, 3) float64 original positions. fallback : (T, P, 3) positions kept where both
the first solve and a cold restart fail (feasible with hard constraints). cold_starts : (T, P, 3)
where chunks start and failed frames restart (feasible with hard constraints), or None: the
original positions, or the fallback with hard constraints.
Returns dict: positions (T, P, 3) float64, values (T,) E, evaluations (T,) int32 (arrays moved
from the core, no copy), failures: list of (frame, reason, fell_back). Deterministic whatever the
thread count. Raises ValueError on a bad shape, invalid options or a non-finite position
(naming frame and point). The GIL is released while solving.)doc");
}

}  // namespace animlod::bindings
