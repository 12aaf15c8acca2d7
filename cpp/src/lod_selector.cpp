// Runtime LoD selection (lod_selector.hpp): projected sphere size, level choice from errors or
// MSFT_screencoverage with a hysteresis dead band, and frame skipping with distance (facial LoD
// paper, seeds/004, Section 4.2.3; motion LoD paper, seeds/000, Section 3 "LoD control").
#include "animlod/lod_selector.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <string>

namespace animlod {

namespace {
constexpr float kInfinity = std::numeric_limits<float>::infinity();
}

float focal_length_pixels(const LodCamera& camera) {
  return camera.viewport_height / (2.0f * std::tan(0.5f * camera.vertical_fov));
}

ProjectedSphere project_sphere(const LodCamera& camera, const glm::vec3& center, float radius) {
  ProjectedSphere out;
  out.distance = glm::length(center - camera.position);
  const float squared = out.distance * out.distance - radius * radius;
  if (squared <= 0.0f) {
    out.coverage = kInfinity;
    return out;
  }
  // The sphere subtends a half-angle asin(r / d); its projection's half-height on the image
  // plane at distance 1 is tan(asin(r / d)) = r / sqrt(d^2 - r^2), and the viewport's is tan(fov / 2).
  out.coverage = radius / (std::sqrt(squared) * std::tan(0.5f * camera.vertical_fov));
  return out;
}

float screen_error_pixels(float error, float distance, float focal_length_px) {
  if (!(distance > 0.0f)) return kInfinity;
  return error / distance * focal_length_px;
}

Status validate_screen_coverages(const float* coverages, size_t level_count) {
  if (level_count == 0) return Status::error("screen coverages: the chain has no level");
  for (size_t i = 0; i < level_count; ++i) {
    const float c = coverages[i];
    if (!std::isfinite(c) || c < 0.0f)
      return Status::error("screen coverages: level " + std::to_string(i) + " has coverage " + std::to_string(c) +
                           ", expected a finite value >= 0");
    if (i > 0 && c > coverages[i - 1])
      return Status::error("screen coverages: level " + std::to_string(i) + " has coverage " + std::to_string(c) +
                           ", above level " + std::to_string(i - 1) + "'s " + std::to_string(coverages[i - 1]) +
                           " (MSFT_screencoverage must not increase)");
  }
  return Status::success();
}

Status validate_level_errors(const float* errors, size_t level_count) {
  if (level_count == 0) return Status::error("level errors: the chain has no level");
  for (size_t i = 0; i < level_count; ++i) {
    if (!std::isfinite(errors[i]) || errors[i] < 0.0f)
      return Status::error("level errors: level " + std::to_string(i) + " has error " + std::to_string(errors[i]) +
                           ", expected a finite value >= 0");
  }
  return Status::success();
}

int level_for_coverage(const float* coverages, size_t level_count, float coverage) {
  assert(level_count > 0);
  for (size_t i = 0; i < level_count; ++i) {
    if (coverage >= coverages[i]) return static_cast<int>(i);
  }
  return static_cast<int>(level_count) - 1;
}

int level_for_error(const float* errors, size_t level_count, float distance, float focal_length_px,
                    float pixel_error) {
  assert(level_count > 0);
  int chosen = 0;
  for (size_t i = 1; i < level_count; ++i) {
    if (screen_error_pixels(errors[i], distance, focal_length_px) <= pixel_error) chosen = static_cast<int>(i);
  }
  return chosen;
}

int LodSelector::settle(int finer, int coarser, size_t level_count) {
  // A level outside the chain (the chain changed since the last call) starts over.
  if (level_ < 0 || level_ >= static_cast<int>(level_count)) {
    level_ = -1;
    return -1;
  }
  // finer <= coarser always: the finer edge looks at a closer (or larger) character.
  level_ = std::clamp(level_, std::min(finer, coarser), std::max(finer, coarser));
  return level_;
}

int LodSelector::select_by_coverage(const float* coverages, size_t level_count, float coverage) {
  const float band = 1.0f + std::max(options_.hysteresis, 0.0f);
  if (settle(level_for_coverage(coverages, level_count, coverage * band),
             level_for_coverage(coverages, level_count, coverage / band), level_count) < 0)
    level_ = level_for_coverage(coverages, level_count, coverage);
  return level_;
}

int LodSelector::select_by_error(const float* errors, size_t level_count, float distance, float focal_length_px) {
  const float band = 1.0f + std::max(options_.hysteresis, 0.0f);
  const float budget = options_.pixel_error;
  if (settle(level_for_error(errors, level_count, distance / band, focal_length_px, budget),
             level_for_error(errors, level_count, distance * band, focal_length_px, budget), level_count) < 0)
    level_ = level_for_error(errors, level_count, distance, focal_length_px, budget);
  return level_;
}

int animation_update_interval(float coverage, const AnimationRateOptions& options) {
  const int longest = std::max(options.max_interval, 1);
  if (coverage >= options.full_rate_coverage) return 1;
  if (!(coverage > 0.0f)) return longest;
  const float ratio = options.full_rate_coverage / coverage;  // > 1, grows with distance
  if (!(ratio < static_cast<float>(longest))) return longest;
  return std::max(1, static_cast<int>(ratio));
}

}  // namespace animlod
