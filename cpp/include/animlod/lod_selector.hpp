// Runtime level-of-detail selection for animated characters: the projected size of a bounding
// sphere, the level from a chain's recorded errors (asset units -> pixels) or from its
// MSFT_screencoverage thresholds, with hysteresis so that a character standing at a threshold
// does not flicker, and an animation update interval (frame skipping) that grows with distance.
//
// Sources: the motion LoD paper (seeds/000, Section 3: "projected size of VH from the camera"
// drives the LoD control) and the facial LoD paper (seeds/004, Section 4.2.3: frame skipping
// rate varied with view distance). The paper's drawback that skipping changes the duration of
// the animation is avoided by the caller: a skipped frame keeps the last pose, and an update
// samples the clip at the current time, so the clip keeps its speed.
//
// GLM is part of this header's API (column-major matrices, as everywhere in the core).
// Everything here is allocation-free and cheap enough to call per character per frame.
#pragma once

#include <cstddef>
#include <cstdint>

#include <glm/glm.hpp>

#include "animlod/status.hpp"

namespace animlod {

// A perspective camera as the selector sees it.
struct LodCamera {
  glm::vec3 position{0.0f};       // asset units, world space
  float vertical_fov = 0.8f;      // radians, the full vertical field of view, in (0, pi)
  float viewport_height = 720.0f; // pixels, > 0
};

// Pixels per asset unit at distance 1 along the view axis: viewport_height / (2 tan(fov / 2)).
// An error e at distance d covers e / d * focal_length_pixels(camera) pixels.
float focal_length_pixels(const LodCamera& camera);

// Size on screen of a bounding sphere seen from `camera`.
struct ProjectedSphere {
  float distance = 0.0f;  // asset units, camera position to the sphere's centre
  // Fraction of the viewport height covered by the sphere's projection (MSFT_screencoverage
  // convention): tan(asin(r / d)) / tan(fov / 2), the exact height of the disc the sphere
  // projects to at the centre of the view. Infinite when the camera is inside the sphere.
  float coverage = 0.0f;
};

// Projects the sphere (centre in world space, radius >= 0 in asset units). The distance is
// Euclidean (not depth), so turning the camera on the spot does not change a character's level.
ProjectedSphere project_sphere(const LodCamera& camera, const glm::vec3& center, float radius);

// Screen-space size in pixels of an error of `error` asset units at `distance` (> 0):
// error / distance * focal_length_px. A zero or negative distance gives +infinity.
float screen_error_pixels(float error, float distance, float focal_length_px);

// Checks an MSFT_screencoverage list before use: L + 1 >= 1 finite values in [0, inf),
// non-increasing. Errors name the first offending entry.
Status validate_screen_coverages(const float* coverages, size_t level_count);

// Checks a per-level error list: L + 1 >= 1 finite values >= 0. (Errors need not be monotone:
// a chain of geometry x motion levels may list a coarse mesh before a fine one.)
Status validate_level_errors(const float* errors, size_t level_count);

// The level an MSFT_screencoverage list asks for, without hysteresis: the finest level i with
// coverage >= coverages[i]; the coarsest level when there is none. `coverages` (L + 1,) must
// pass validate_screen_coverages (asserted in debug builds only).
int level_for_coverage(const float* coverages, size_t level_count, float coverage);

// The level recorded errors ask for, without hysteresis: the coarsest level i whose error
// projects to at most `pixel_error` pixels at `distance` (errors[i] / distance * focal_px);
// level 0 when none does. `errors` (L + 1,) in asset units, as the chain records them.
int level_for_error(const float* errors, size_t level_count, float distance, float focal_length_px,
                    float pixel_error);

// How LodSelector switches levels: the dead band and the screen-space error budget.
struct LodSelectorOptions {
  // Relative dead band around every threshold: a character moves to a coarser level only when
  // its metric has passed the threshold by this factor (coverage below c / (1 + h), or distance
  // beyond d * (1 + h)), and back to the finer level only when it has come back past c * (1 + h)
  // (or d / (1 + h)). 0 switches exactly at the thresholds. Must be >= 0.
  float hysteresis = 0.15f;
  // Screen-space error budget in pixels for select_by_error.
  float pixel_error = 1.0f;
};

// Per-instance selection state (one per character): the level it shows now, kept while the
// camera moves inside a threshold's dead band. Copyable, 8 bytes of state plus the options.
class LodSelector {
 public:
  explicit LodSelector(const LodSelectorOptions& options = {}) : options_(options) {}

  // The level for projected coverage `coverage` with an MSFT_screencoverage list (L + 1,),
  // with hysteresis. The first call (or the first after reset) returns level_for_coverage.
  int select_by_coverage(const float* coverages, size_t level_count, float coverage);

  // The level for a character at `distance` from the camera, from per-level errors (L + 1,)
  // in asset units and the options' pixel budget, with hysteresis.
  int select_by_error(const float* errors, size_t level_count, float distance, float focal_length_px);

  int level() const { return level_; }  // -1 before the first selection
  void reset() { level_ = -1; }
  const LodSelectorOptions& options() const { return options_; }

 private:
  // Keeps level_ inside [finer, coarser], the levels the dead band's two edges ask for.
  int settle(int finer, int coarser, size_t level_count);

  LodSelectorOptions options_;
  int level_ = -1;
};

// How animation_update_interval lowers the pose update rate of small characters.
struct AnimationRateOptions {
  // At or above this projected coverage (fraction of the viewport height) the pose is updated
  // every frame. Must be > 0.
  float full_rate_coverage = 0.25f;
  // The longest interval between two pose updates, in frames (>= 1).
  int max_interval = 8;
};

// Frames between pose updates for a character of projected `coverage`: 1 at or above
// full_rate_coverage, then floor(full_rate_coverage / coverage), so the update rate falls in
// proportion to 1 / distance, capped at max_interval (also for coverage <= 0).
int animation_update_interval(float coverage, const AnimationRateOptions& options = {});

// Whether instance `instance` updates its pose at frame `frame` when it updates every
// `interval` frames (interval >= 1). Instances are staggered by their index, so that with
// many characters the work is spread evenly over the frames instead of bunching up.
inline bool animation_update_due(uint64_t frame, uint32_t instance, int interval) {
  return interval <= 1 || (frame + instance) % static_cast<uint64_t>(interval) == 0;
}

}  // namespace animlod
