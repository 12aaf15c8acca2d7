// Python binding of posture_error.hpp (Eq. 1 of motion analysis).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "animlod/posture_error.hpp"
#include "array_checks.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

py::array_t<double> posture_error_row_sums_py(const DoubleArray& directions, const DoubleArray& radii,
                                              unsigned threads) {
  require_shape(directions, "directions", {-1, -1, 3}, "(n, B, 3)");
  require_shape(radii, "radii", {directions.shape(0), directions.shape(1)}, "(n, B) like directions");
  const auto frames = static_cast<size_t>(directions.shape(0));
  const auto bones = static_cast<size_t>(directions.shape(1));
  py::array_t<double> out({directions.shape(1), directions.shape(0)});
  call_released([&] {
    return posture_error_row_sums(directions.data(), radii.data(), frames, bones, threads, out.mutable_data());
  });
  return out;
}

}  // namespace

void bind_posture_error(py::module_& m) {
  m.def("posture_error_row_sums", &posture_error_row_sums_py, py::arg("directions"), py::arg("radii"),
        py::arg("threads") = 0u,
        R"doc(Row sums of the posture error table (seeds/000, Eq. 1), one bone at a time.

Parameters
----------
directions : (n, B, 3) float64 unit (or zero) direction of each of B bones at n frames.
radii : (n, B) float64 the bones' lengths.
threads : threads sharing the bones (0: :func:`thread_limit`); the result does not depend on it.

Returns
-------
(B, n) float64: out[c, a] = sum_b (r_c(a) + r_c(b)) / 2 * theta_c(a, b), the arc lengths of the
bone's turn between frame a and every frame b (before Eq. 1's division by 2 pi r_max).
Raises ValueError on a wrong shape or a non-finite value (naming the frame and the bone).)doc");
}

}  // namespace animlod::bindings
