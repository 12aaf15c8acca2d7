// Python binding of decimal_rows.hpp (the OBJ writer's v, vt and vn lines).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "animlod/decimal_rows.hpp"
#include "array_checks.hpp"

namespace animlod::bindings {

namespace {

py::bytes decimal_rows_py(const DoubleArray& values, const std::string& prefix, int digits) {
  require_shape(values, "values", {-1, -1}, "(N, K)");
  if (digits < 1 || digits > 17) throw py::value_error("digits: expected 1 to 17, got " + std::to_string(digits));
  std::string text;
  {
    py::gil_scoped_release release;
    text = decimal_rows(values.data(), static_cast<size_t>(values.shape(0)), static_cast<size_t>(values.shape(1)),
                        prefix, digits);
  }
  return py::bytes(text);
}

}  // namespace

void bind_decimal_rows(py::module_& m) {
  m.def("decimal_rows", &decimal_rows_py, py::arg("values"), py::arg("prefix"), py::arg("digits") = 9,
        R"doc(Rows of numbers as lines of text: for each row of ``values`` (N, K) (float64; other
types converted), ``prefix``, then each value as ``"%.<digits>g" % value`` writes it, separated by
one space, then a newline; as bytes (ASCII). ``digits`` is 1 to 17: 9 round-trips a float32, 17 a
double.)doc");
}

}  // namespace animlod::bindings
