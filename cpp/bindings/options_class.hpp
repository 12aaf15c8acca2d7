// OptionsClass: the one way a core options struct becomes a Python class. Fields are
// read-write (a vector field reads as a tuple), their defaults are the struct's, their
// docstrings the header comments (header_docs.hpp); the class takes keyword arguments (also for
// the fields of nested options), refuses an unknown name or a value of the wrong type with a
// ValueError naming the option, and compares, prints, copies and pickles by its fields (Dask
// sends options to workers).
#pragma once

#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/typing.h>

#include "enum_names.hpp"
#include "header_docs.hpp"

namespace animlod::bindings {

namespace py = pybind11;

namespace detail {

// What a field holds, for the message of a value it cannot take ("a number", "numbers").
template <class T>
std::string value_kind(bool plural = false) {
  const char* article = plural ? "" : "a ";
  const char* s = plural ? "s" : "";
  if constexpr (std::is_same_v<T, bool>) return "True or False";
  else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>)
    return std::string(plural ? "" : "an ") + "integer" + s + " >= 0";
  else if constexpr (std::is_integral_v<T>) return std::string(plural ? "" : "an ") + "integer" + s;
  else if constexpr (std::is_floating_point_v<T>) return std::string(article) + "number" + s;
  else if constexpr (std::is_same_v<T, std::string>) return std::string(article) + "string" + s;
  else return std::string(article) + "list" + s + " of " + value_kind<typename T::value_type>(true);
}

template <class T>
struct is_vector : std::false_type {};
template <class T>
struct is_vector<std::vector<T>> : std::true_type {};

// What reading a field gives. Reading hands out a copy of the struct's value, so a vector reads
// as a tuple: a list there took `opts.frame_subset.append(3)` and changed nothing.
template <class T>
auto readable(const T& value) {
  if constexpr (is_vector<T>::value) {
    using Item = std::conditional_t<std::is_floating_point_v<typename T::value_type>, py::float_, py::int_>;
    return py::typing::Tuple<Item, py::ellipsis>(py::cast(value));
  } else {
    return value;
  }
}

inline std::string repr_text(const py::handle& value) { return std::string(py::str(py::repr(value))); }
inline std::string text(const py::handle& value) { return std::string(py::str(value)); }

// Names, kinds and nested option fields of one class, shared by its update, repr, == and pickle.
struct OptionsLayout {
  std::string class_name;
  std::vector<std::pair<std::string, std::string>> fields;  // name, what it holds
  std::vector<std::string> nested;                          // fields that are options themselves

  // Sets the field `name` of `self` or of one of its nested options.
  void set(py::object self, const std::string& name, const py::handle& value) const {
    for (const auto& [field, kind] : fields) {
      if (field != name) continue;
      try {
        py::setattr(self, name.c_str(), value);
      } catch (py::error_already_set& error) {
        if (!error.matches(PyExc_TypeError)) throw;
        throw py::value_error(class_name + "." + name + ": expected " + kind + ", got " +
                              detail::repr_text(value));
      }
      return;
    }
    for (const std::string& field : nested) {
      py::object inner = self.attr(field.c_str());
      if (inner.attr("fields").contains(name)) {
        py::dict keyword;
        keyword[name.c_str()] = value;
        inner.attr("update")(**keyword);
        return;
      }
    }
    std::string known;
    for (const auto& field : fields) known += (known.empty() ? "" : ", ") + field.first;
    for (const std::string& field : nested) known += ", the fields of " + field;
    throw py::value_error(class_name + ": unknown option '" + name + "' (options: " + known + ")");
  }

  // Sets every (name, value) of `values`, as `set` does.
  void update(const py::object& self, const py::dict& values) const {
    for (const auto& [name, value] : values) set(self, text(name), value);
  }

  py::dict state(const py::object& self) const {
    py::dict out;
    for (const auto& field : fields) out[field.first.c_str()] = self.attr(field.first.c_str());
    return out;
  }
};

}  // namespace detail

template <class Options>
class OptionsClass {
 public:
  OptionsClass(py::module_& m, const char* name)
      : layout_(std::make_shared<detail::OptionsLayout>()), cls_(m, name, header_docs::doc(name).data()) {
    layout_->class_name = name;
  }

  // A plain field.
  template <class T>
  OptionsClass& field(const char* name, T Options::*member) {
    cls_.def_property(
        name, [member](const Options& o) { return detail::readable(o.*member); },
        [member](Options& o, T value) { o.*member = std::move(value); }, field_doc<T>(name).c_str());
    layout_->fields.emplace_back(name, detail::value_kind<T>());
    return *this;
  }

  // A field whose values the core reads without a Status to refuse them: `check(value)` returns
  // what is wrong with a value ("must be >= 0"), empty when it is fine.
  template <class T, class Check>
  OptionsClass& checked_field(const char* name, T Options::*member, Check check) {
    const std::string where = layout_->class_name + "." + name;
    cls_.def_property(
        name, [member](const Options& o) { return detail::readable(o.*member); },
        [member, check, where](Options& o, T value) {
          const std::string problem = check(value);
          if (!problem.empty()) throw py::value_error(where + ": " + problem + ", got " + detail::repr_text(py::cast(value)));
          o.*member = value;
        },
        field_doc<T>(name).c_str());
    layout_->fields.emplace_back(name, detail::value_kind<T>());
    return *this;
  }

  // An enum field, as the name of its value ("optimal", "on_edge", ...).
  template <class Enum>
  OptionsClass& choice(const char* name, Enum Options::*member) {
    const std::string where = layout_->class_name + "." + name;
    std::string text = doc(name);
    const auto& values = header_docs::EnumValues<Enum>::values;
    for (size_t i = 0; i < values.size(); ++i)
      text += "\n- '" + std::string(values[i].second) + "': " + std::string(header_docs::EnumValues<Enum>::docs[i]);
    cls_.def_property(
        name, [member](const Options& o) { return enum_name(o.*member); },
        [member, where](Options& o, const std::string& value) { o.*member = enum_from_name<Enum>(value, where); },
        text.c_str());
    layout_->fields.emplace_back(name, "one of " + enum_choices<Enum>());
    return *this;
  }

  // Options of a nested struct; its fields may also be given by name to the outer class.
  template <class Nested>
  OptionsClass& nested(const char* name, Nested Options::*member) {
    cls_.def_readwrite(name, member, doc(name).c_str());
    layout_->fields.emplace_back(name, std::string("a ") + detail::text(py::type::of<Nested>().attr("__name__")));
    layout_->nested.emplace_back(name);
    return *this;
  }

  // Construction from keywords, update, ==, repr, copy and pickling; call after the fields.
  py::class_<Options>& finish() {
    const std::shared_ptr<const detail::OptionsLayout> layout = layout_;
    py::tuple names(layout->fields.size());
    for (size_t i = 0; i < layout->fields.size(); ++i) names[i] = py::str(layout->fields[i].first);
    cls_.attr("fields") = names;
    // The struct's defaults changed by `values`, set through the Python fields so that they
    // are checked and named like any other assignment.
    const auto made_from = [layout](const py::dict& values) {
      py::object made = py::cast(Options{});
      layout->update(made, values);
      return made.cast<Options>();
    };
    cls_.def(py::init([made_from](const py::kwargs& values) { return made_from(values); }),
             "Options with the defaults of the C++ struct, changed by keyword (a field of this class or of its "
             "nested options).")
        .def(
            "update",
            [layout](const py::object& self, const py::kwargs& values) { layout->update(self, values); },
            "Set fields by keyword (a field of this class or of its nested options); ValueError naming an unknown "
            "option or a value of the wrong kind.")
        .def("__eq__",
             [layout](const py::object& self, const py::object& other) {
               return py::type::of(self).is(py::type::of(other)) && layout->state(self).equal(layout->state(other));
             })
        .def("__repr__",
             [layout](const py::object& self) {
               std::string text = layout->class_name + "(";
               for (const auto& [name, value] : layout->state(self))
                 text += (text.back() == '(' ? "" : ", ") + detail::text(name) + "=" +
                         detail::repr_text(value);
               return text + ")";
             })
        .def("__copy__", [](const Options& self) { return Options(self); })
        .def("__deepcopy__", [](const Options& self, const py::dict&) { return Options(self); }, py::arg("memo"))
        .def(py::pickle([layout](const py::object& self) { return layout->state(self); }, made_from));
    return cls_;
  }

 private:
  template <class T>
  std::string field_doc(const char* field) const {
    if constexpr (detail::is_vector<T>::value)
      return doc(field) + "\n\nRead as a tuple, a copy of the C++ vector; assign a sequence to change the field.";
    else
      return doc(field);
  }

  std::string doc(const char* field) const {
    return std::string(header_docs::doc(layout_->class_name + "." + field));
  }

  std::shared_ptr<detail::OptionsLayout> layout_;
  py::class_<Options> cls_;
};

}  // namespace animlod::bindings
