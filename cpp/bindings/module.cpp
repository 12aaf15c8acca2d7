// animlod._core: thin pybind11 bindings over the C++ core, one bind_<concept>.cpp per header.
#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace animlod::bindings {
void bind_options(py::module_& m);
void bind_skinning(py::module_& m);
void bind_aqem(py::module_& m);
void bind_motion_features(py::module_& m);
void bind_ffd_lattice(py::module_& m);
void bind_motion_refit(py::module_& m);
void bind_tdag(py::module_& m);
void bind_lod_selector(py::module_& m);
void bind_pose(py::module_& m);
void bind_point_mesh_distance(py::module_& m);
void bind_posture_error(py::module_& m);
void bind_cumulative_ranking(py::module_& m);
void bind_motion_recovery(py::module_& m);
void bind_threads(py::module_& m);
void bind_decimal_rows(py::module_& m);
}

PYBIND11_MODULE(_core, m) {
  m.doc() = "animlod C++ core (level of detail for animated content). Users import animlod.";
  animlod::bindings::bind_options(m);  // first: the functions below take these classes
  animlod::bindings::bind_skinning(m);
  animlod::bindings::bind_aqem(m);
  animlod::bindings::bind_motion_features(m);
  animlod::bindings::bind_ffd_lattice(m);
  animlod::bindings::bind_motion_refit(m);
  animlod::bindings::bind_tdag(m);
  animlod::bindings::bind_lod_selector(m);
  animlod::bindings::bind_pose(m);
  animlod::bindings::bind_point_mesh_distance(m);
  animlod::bindings::bind_posture_error(m);
  animlod::bindings::bind_cumulative_ranking(m);
  animlod::bindings::bind_motion_recovery(m);
  animlod::bindings::bind_threads(m);
  animlod::bindings::bind_decimal_rows(m);
}
