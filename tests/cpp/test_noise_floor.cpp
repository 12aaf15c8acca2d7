#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "noise_floor.hpp"
#include "test_aqem_meshes.hpp"

using animlod::detail::frame_noise_floor;
using animlod::testing::OwnedAnimatedMesh;

namespace {

// grid(16) (the unit square, diagonal sqrt 2) in `frames` frames: turned about z and moved by
// frame, each coordinate then jittered by Gaussian noise of `noise`.
OwnedAnimatedMesh moving_grid(size_t frames, double noise) {
  OwnedAnimatedMesh mesh = animlod::testing::grid(16);
  const std::vector<float> rest = mesh.frames;
  std::mt19937 random(7);
  std::normal_distribution<double> jitter(0.0, noise);
  mesh.frames.clear();
  for (size_t frame = 0; frame < frames; ++frame) {
    const double angle = 0.2 * double(frame), c = std::cos(angle), s = std::sin(angle);
    for (size_t v = 0; v < mesh.vertex_count; ++v) {
      const double x = rest[3 * v], y = rest[3 * v + 1];
      mesh.frames.push_back(float(c * x - s * y + 0.1 * double(frame) + jitter(random)));
      mesh.frames.push_back(float(s * x + c * y + jitter(random)));
      mesh.frames.push_back(float(0.05 * double(frame) + jitter(random)));
    }
  }
  mesh.frame_count = frames;
  return mesh;
}

}  // namespace

TEST_CASE("the noise floor of a rigidly moving mesh is float rounding") {
  CHECK(frame_noise_floor(moving_grid(8, 0.0).view()) < 1e-7);
}

TEST_CASE("the noise floor measures Gaussian noise on the coordinates") {
  // An edge's length moves by about the noise: its ends' noise along the edge, sqrt 2 times
  // the noise, and the 10th percentile of the edges' sample deviations sits below their mean.
  const double noise = 1e-3;
  const double floor = frame_noise_floor(moving_grid(16, noise).view()) * std::sqrt(2.0);
  CHECK(floor > 0.5 * noise);
  CHECK(floor < 2.0 * noise);
}

TEST_CASE("one frame has no noise floor") {
  CHECK(frame_noise_floor(moving_grid(1, 1e-3).view()) == 0.0);
}
