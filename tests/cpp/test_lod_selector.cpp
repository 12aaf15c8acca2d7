#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "animlod/lod_selector.hpp"

namespace {
const std::vector<float> kCoverages = {0.5f, 0.25f, 0.1f, 0.0f};
const std::vector<float> kErrors = {0.0f, 0.01f, 0.04f, 0.16f};
}  // namespace

TEST_CASE("project_sphere gives the exact projected height of a sphere") {
  animlod::LodCamera camera;
  camera.vertical_fov = 2.0f * std::atan(0.5f);  // tan(fov / 2) = 0.5
  camera.viewport_height = 1000.0f;
  const animlod::ProjectedSphere far = animlod::project_sphere(camera, {0.0f, 0.0f, -10.0f}, 1.0f);
  CHECK(far.distance == doctest::Approx(10.0f));
  // tan(asin(1 / 10)) / 0.5 = (1 / sqrt(99)) / 0.5
  CHECK(far.coverage == doctest::Approx(2.0 / std::sqrt(99.0)).epsilon(1e-6));
  CHECK(animlod::focal_length_pixels(camera) == doctest::Approx(1000.0f));
  CHECK(animlod::screen_error_pixels(0.01f, 10.0f, 1000.0f) == doctest::Approx(1.0f));
  // Inside the sphere: infinite coverage, finest level.
  const animlod::ProjectedSphere inside = animlod::project_sphere(camera, {0.0f, 0.0f, -0.5f}, 1.0f);
  CHECK(std::isinf(inside.coverage));
  CHECK(animlod::level_for_coverage(kCoverages.data(), kCoverages.size(), inside.coverage) == 0);
}

TEST_CASE("level_for_coverage follows MSFT_screencoverage: level i while coverage >= c_i") {
  const float* c = kCoverages.data();
  CHECK(animlod::level_for_coverage(c, 4, 0.9f) == 0);
  CHECK(animlod::level_for_coverage(c, 4, 0.5f) == 0);
  CHECK(animlod::level_for_coverage(c, 4, 0.49f) == 1);
  CHECK(animlod::level_for_coverage(c, 4, 0.1f) == 2);
  CHECK(animlod::level_for_coverage(c, 4, 0.01f) == 3);
}

TEST_CASE("level_for_error picks the coarsest level within the pixel budget") {
  const float* e = kErrors.data();
  // focal 1000 px: level 1 (0.01) is 1 px at 10, level 2 (0.04) at 40, level 3 (0.16) at 160.
  CHECK(animlod::level_for_error(e, 4, 5.0f, 1000.0f, 1.0f) == 0);
  CHECK(animlod::level_for_error(e, 4, 10.0f, 1000.0f, 1.0f) == 1);
  CHECK(animlod::level_for_error(e, 4, 39.0f, 1000.0f, 1.0f) == 1);
  CHECK(animlod::level_for_error(e, 4, 41.0f, 1000.0f, 1.0f) == 2);
  CHECK(animlod::level_for_error(e, 4, 1000.0f, 1000.0f, 1.0f) == 3);
  CHECK(animlod::level_for_error(e, 4, 0.0f, 1000.0f, 1.0f) == 0);
}

TEST_CASE("validators name the offending level") {
  const std::vector<float> rising = {0.5f, 0.6f, 0.0f};
  animlod::Status status = animlod::validate_screen_coverages(rising.data(), rising.size());
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("level 1") != std::string::npos);
  const std::vector<float> negative = {0.0f, -1.0f};
  status = animlod::validate_level_errors(negative.data(), negative.size());
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("level 1") != std::string::npos);
  CHECK(animlod::validate_screen_coverages(kCoverages.data(), kCoverages.size()).ok);
  CHECK(animlod::validate_level_errors(kErrors.data(), kErrors.size()).ok);
  CHECK_FALSE(animlod::validate_level_errors(nullptr, 0).ok);
}

// Sweeps the distance from 5 to 300 and back in small steps and counts level changes. Without
// hysteresis a character jittering around a threshold flips at every step; with it, each
// threshold is crossed once each way.
TEST_CASE("LodSelector: no flicker when a character jitters at a threshold") {
  const float focal = 1000.0f;
  for (float hysteresis : {0.0f, 0.15f}) {
    animlod::LodSelector selector({hysteresis, 1.0f});
    int changes = 0, last = -1;
    // Oscillate +-2% around the level 1 -> 2 threshold at distance 40.
    for (int step = 0; step < 100; ++step) {
      const float distance = 40.0f * (step % 2 ? 1.02f : 0.98f);
      const int level = selector.select_by_error(kErrors.data(), kErrors.size(), distance, focal);
      if (last >= 0 && level != last) ++changes;
      last = level;
    }
    if (hysteresis == 0.0f) CHECK(changes == 99);  // the control: flips at every step
    else CHECK(changes == 0);
  }
}

TEST_CASE("LodSelector: a sweep out and back switches each threshold once each way") {
  animlod::LodSelector selector;  // hysteresis 0.15
  std::vector<int> levels;
  for (int i = 0; i <= 400; ++i) {
    const float coverage = 0.8f * std::pow(0.98f, static_cast<float>(i));  // away from the camera
    levels.push_back(selector.select_by_coverage(kCoverages.data(), kCoverages.size(), coverage));
  }
  for (int i = 400; i >= 0; --i) {
    const float coverage = 0.8f * std::pow(0.98f, static_cast<float>(i));  // and back
    levels.push_back(selector.select_by_coverage(kCoverages.data(), kCoverages.size(), coverage));
  }
  int changes = 0;
  for (size_t i = 1; i < levels.size(); ++i) {
    CHECK(std::abs(levels[i] - levels[i - 1]) <= 1);
    changes += levels[i] != levels[i - 1];
  }
  CHECK(levels.front() == 0);
  CHECK(levels[400] == 3);
  CHECK(levels.back() == 0);
  CHECK(changes == 6);
  // Moving away, level 1 starts below c_0 / 1.15, not at c_0.
  for (int i = 0; i <= 400; ++i) {
    const float coverage = 0.8f * std::pow(0.98f, static_cast<float>(i));
    if (levels[i] == 1 && (i == 0 || levels[i - 1] == 0)) CHECK(coverage < 0.5f / 1.15f);
  }
}

TEST_CASE("LodSelector starts over when the chain shrinks below its level") {
  animlod::LodSelector selector({0.15f, 1.0f});
  CHECK(selector.level() == -1);
  CHECK(selector.select_by_coverage(kCoverages.data(), 4, 0.01f) == 3);
  const std::vector<float> two = {0.3f, 0.0f};
  CHECK(selector.select_by_coverage(two.data(), two.size(), 0.5f) == 0);
  selector.reset();
  CHECK(selector.level() == -1);
}

TEST_CASE("animation_update_interval falls with distance and is capped") {
  animlod::AnimationRateOptions options;  // full rate at 0.25, at most 8
  CHECK(animlod::animation_update_interval(0.5f, options) == 1);
  CHECK(animlod::animation_update_interval(0.25f, options) == 1);
  CHECK(animlod::animation_update_interval(0.125f, options) == 2);
  CHECK(animlod::animation_update_interval(0.08f, options) == 3);
  CHECK(animlod::animation_update_interval(0.001f, options) == 8);
  CHECK(animlod::animation_update_interval(0.0f, options) == 8);
  int previous = 1;
  for (float coverage = 1.0f; coverage > 1e-4f; coverage *= 0.9f) {
    const int interval = animlod::animation_update_interval(coverage, options);
    CHECK(interval >= previous);
    previous = interval;
  }
  // Staggered: over `interval` frames each instance updates exactly once.
  for (uint32_t instance = 0; instance < 10; ++instance) {
    int updates = 0;
    for (uint64_t frame = 100; frame < 103; ++frame) updates += animlod::animation_update_due(frame, instance, 3);
    CHECK(updates == 1);
  }
  CHECK(animlod::animation_update_due(7, 3, 1));
}
