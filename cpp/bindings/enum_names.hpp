// The Python names of the core's enums: each value's C++ name, read from the headers by
// gen_header_docs.py (EnumValues), so that a name exists once.
#pragma once

#include <string>
#include <string_view>

#include <pybind11/pybind11.h>

#include "header_docs.hpp"

namespace animlod::bindings {

template <class Enum>
std::string enum_name(Enum value) {
  for (const auto& [candidate, name] : header_docs::EnumValues<Enum>::values)
    if (candidate == value) return std::string(name);
  return "?";
}

// "'optimal', 'on_edge'" for messages and docstrings.
template <class Enum>
std::string enum_choices() {
  std::string text;
  for (const auto& [value, name] : header_docs::EnumValues<Enum>::values)
    text += (text.empty() ? "'" : ", '") + std::string(name) + "'";
  return text;
}

// The value called `name`; a ValueError "WHERE: expected one of ..., got 'NAME'" otherwise.
template <class Enum>
Enum enum_from_name(const std::string& name, const std::string& where) {
  for (const auto& [value, candidate] : header_docs::EnumValues<Enum>::values)
    if (candidate == name) return value;
  throw pybind11::value_error(where + ": expected one of " + enum_choices<Enum>() + ", got '" + name + "'");
}

}  // namespace animlod::bindings
