// The Python names of animlod::FeatureWeighting, shared by bind_aqem and bind_motion_features.
#pragma once

#include <string>

#include <pybind11/pybind11.h>

#include "animlod/motion_features.hpp"

namespace animlod::bindings {

// "amplitude" or "paper"; anything else raises ValueError naming the parameter.
inline FeatureWeighting feature_weighting_from_name(const std::string& name) {
  if (name == "amplitude") return FeatureWeighting::amplitude;
  if (name == "paper") return FeatureWeighting::paper;
  throw pybind11::value_error("feature_weighting: expected 'amplitude' or 'paper', got '" + name + "'");
}

}  // namespace animlod::bindings
