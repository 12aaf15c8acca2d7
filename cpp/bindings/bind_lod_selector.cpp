// Python bindings of lod_selector.hpp: options structs with read-write fields whose defaults
// come from the C++ structs, the per-instance LodSelector, and the free functions. Lists of
// per-level errors or coverages are validated before use (ValueError naming the level).
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "animlod/lod_selector.hpp"
#include "array_checks.hpp"

namespace animlod::bindings {

namespace {

using FloatVector = py::array_t<float, py::array::c_style | py::array::forcecast>;

FloatVector level_values(const py::object& values, const char* name, bool coverages) {
  FloatVector array = FloatVector::ensure(values);
  if (!array) throw py::value_error(std::string(name) + ": expected a sequence of numbers");
  require_shape(array, name, {-1}, "(L + 1,)");
  const auto count = static_cast<size_t>(array.shape(0));
  raise_if_error(coverages ? validate_screen_coverages(array.data(), count) : validate_level_errors(array.data(), count));
  return array;
}

glm::vec3 vec3_from(const std::vector<float>& values, const char* name) {
  if (values.size() != 3)
    throw py::value_error(std::string(name) + ": expected 3 values, got " + std::to_string(values.size()));
  return {values[0], values[1], values[2]};
}

void check_camera(const LodCamera& camera) {
  if (!(camera.vertical_fov > 0.0f && camera.vertical_fov < 3.14159265f))
    throw py::value_error("camera: vertical_fov must lie in (0, pi) radians, got " + std::to_string(camera.vertical_fov));
  if (!(camera.viewport_height > 0.0f))
    throw py::value_error("camera: viewport_height must be > 0 pixels, got " + std::to_string(camera.viewport_height));
}

}  // namespace

void bind_lod_selector(py::module_& m) {
  py::class_<LodCamera>(m, "LodCamera", "A perspective camera as the LoD selector sees it.")
      .def(py::init([](const std::vector<float>& position, float vertical_fov, float viewport_height) {
             LodCamera camera;
             camera.position = vec3_from(position, "position");
             camera.vertical_fov = vertical_fov;
             camera.viewport_height = viewport_height;
             check_camera(camera);
             return camera;
           }),
           py::arg("position") = std::vector<float>{0.0f, 0.0f, 0.0f}, py::arg("vertical_fov") = LodCamera{}.vertical_fov,
           py::arg("viewport_height") = LodCamera{}.viewport_height,
           "position: (3,) world position in asset units; vertical_fov: full vertical field of view in radians; "
           "viewport_height: pixels.")
      .def_property(
          "position", [](const LodCamera& c) { return std::vector<float>{c.position.x, c.position.y, c.position.z}; },
          [](LodCamera& c, const std::vector<float>& p) { c.position = vec3_from(p, "position"); },
          "(3,) world position in asset units (a copy).")
      .def_readwrite("vertical_fov", &LodCamera::vertical_fov, "Full vertical field of view, radians.")
      .def_readwrite("viewport_height", &LodCamera::viewport_height, "Viewport height, pixels.");

  py::class_<ProjectedSphere>(m, "ProjectedSphere", "Size on screen of a bounding sphere.")
      .def_readonly("distance", &ProjectedSphere::distance, "Camera to centre, asset units.")
      .def_readonly("coverage", &ProjectedSphere::coverage,
                    "Fraction of the viewport height covered (MSFT_screencoverage convention); inf inside the sphere.");

  m.def(
      "focal_length_pixels",
      [](const LodCamera& camera) {
        check_camera(camera);
        return focal_length_pixels(camera);
      },
      py::arg("camera"), "Pixels per asset unit at distance 1: viewport_height / (2 tan(vertical_fov / 2)).");

  m.def(
      "project_sphere",
      [](const LodCamera& camera, const std::vector<float>& center, float radius) {
        check_camera(camera);
        if (!(radius >= 0.0f)) throw py::value_error("radius: must be >= 0, got " + std::to_string(radius));
        return project_sphere(camera, vec3_from(center, "center"), radius);
      },
      py::arg("camera"), py::arg("center"), py::arg("radius"),
      R"doc(Projects a bounding sphere (centre (3,) world space, radius in asset units).

Returns a ProjectedSphere: Euclidean distance to the centre and coverage, the fraction of the
viewport height its projection covers, tan(asin(r / d)) / tan(fov / 2); inf when the camera is
inside the sphere.)doc");

  m.def("screen_error_pixels", &screen_error_pixels, py::arg("error"), py::arg("distance"), py::arg("focal_length_px"),
        "Pixels covered by an error (asset units) at a distance: error / distance * focal_length_px; inf for "
        "distance <= 0.");

  m.def(
      "level_for_coverage",
      [](const py::object& coverages, float coverage) {
        const FloatVector c = level_values(coverages, "coverages", true);
        return level_for_coverage(c.data(), static_cast<size_t>(c.shape(0)), coverage);
      },
      py::arg("coverages"), py::arg("coverage"),
      R"doc(Level an MSFT_screencoverage list (L + 1,) asks for at a projected coverage, without
hysteresis: the finest level i with coverage >= coverages[i], else the coarsest.
ValueError (naming the level) when the list is empty, negative, non-finite or increasing.)doc");

  m.def(
      "level_for_error",
      [](const py::object& errors, float distance, float focal_length_px, float pixel_error) {
        const FloatVector e = level_values(errors, "errors", false);
        return level_for_error(e.data(), static_cast<size_t>(e.shape(0)), distance, focal_length_px, pixel_error);
      },
      py::arg("errors"), py::arg("distance"), py::arg("focal_length_px"), py::arg("pixel_error") = 1.0f,
      R"doc(Level per-level errors (L + 1,) in asset units ask for at a distance, without
hysteresis: the coarsest level whose error / distance * focal_length_px <= pixel_error; 0 when
none fits. ValueError (naming the level) on an empty, negative or non-finite list.)doc");

  py::class_<LodSelector>(m, "LodSelector",
                          "Per-character LoD state: the level shown now, kept inside each threshold's dead band so "
                          "that a character at a threshold does not flicker.")
      .def(py::init<const LodSelectorOptions&>(), py::arg("options") = LodSelectorOptions{})
      .def(
          "select_by_coverage",
          [](LodSelector& self, const py::object& coverages, float coverage) {
            const FloatVector c = level_values(coverages, "coverages", true);
            return self.select_by_coverage(c.data(), static_cast<size_t>(c.shape(0)), coverage);
          },
          py::arg("coverages"), py::arg("coverage"),
          "Level for a projected coverage with an MSFT_screencoverage list (L + 1,), with hysteresis.")
      .def(
          "select_by_error",
          [](LodSelector& self, const py::object& errors, float distance, float focal_length_px) {
            const FloatVector e = level_values(errors, "errors", false);
            return self.select_by_error(e.data(), static_cast<size_t>(e.shape(0)), distance, focal_length_px);
          },
          py::arg("errors"), py::arg("distance"), py::arg("focal_length_px"),
          "Level for a character at a distance from per-level errors (L + 1,) in asset units and the options' "
          "pixel budget, with hysteresis.")
      .def_property_readonly("level", &LodSelector::level, "The level shown now; -1 before the first selection.")
      .def_property_readonly("options", &LodSelector::options)
      .def("reset", &LodSelector::reset, "Forget the level (the next selection has no hysteresis).");

  m.def("animation_update_interval", &animation_update_interval, py::arg("coverage"),
        py::arg("options") = AnimationRateOptions{},
        "Frames between pose updates at a projected coverage: 1 at or above full_rate_coverage, then "
        "floor(full_rate_coverage / coverage) (falling with 1 / distance), at most max_interval.");
  m.def("animation_update_due", &animation_update_due, py::arg("frame"), py::arg("instance"), py::arg("interval"),
        "Whether an instance updating every `interval` frames updates at `frame` (staggered by instance index).");
}

}  // namespace animlod::bindings
