#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "animlod/mesh_validation.hpp"
#include "animlod/motion_features.hpp"
#include "test_aqem_meshes.hpp"

using animlod::FeatureWeighting;
using animlod::MotionFeatureOptions;
using animlod::MotionFeatures;
using animlod::testing::OwnedAnimatedMesh;

namespace {
MotionFeatures features_of(const OwnedAnimatedMesh& mesh, const MotionFeatureOptions& options) {
  MotionFeatures features;
  const animlod::Status status = animlod::compute_motion_features(mesh.view(), options, features);
  REQUIRE_MESSAGE(status.ok, status.message);
  return features;
}
constexpr double kPi = 3.14159265358979323846;
}  // namespace

TEST_CASE("motion features measure the change of a hinge's dihedral angle exactly") {
  // Two triangles on the edge (0, 1); frame 1 folds triangle (1, 0, 3) up by 30 degrees.
  OwnedAnimatedMesh mesh;
  const float c = float(std::cos(kPi / 6)), s = float(std::sin(kPi / 6));
  mesh.frames = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0,
                 0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -c, s};
  mesh.faces = {0, 1, 2, 1, 0, 3};
  mesh.frame_count = 2;
  mesh.vertex_count = 4;
  MotionFeatureOptions options;
  options.boundary_is_feature = false;
  options.feature_threshold = 0.1;
  options.feature_weighting = FeatureWeighting::paper;
  const MotionFeatures features = features_of(mesh, options);
  REQUIRE(features.edges.size() == 10);
  CHECK(features.edges[0] == 0);  // edges sorted: (0, 1) first
  CHECK(features.edges[1] == 1);
  CHECK(features.angle_change[0] == doctest::Approx(kPi / 6));
  for (size_t e = 1; e < 5; ++e) CHECK(features.angle_change[e] == 0.0f);
  CHECK(features.connected == std::vector<uint8_t>{1, 0, 0, 0, 0});
  CHECK(features.feature_sizes == std::vector<int32_t>{2});
  CHECK(features.vertex_weights == std::vector<float>{2, 2, 1, 1});
  CHECK(features.vertex_feature == std::vector<int32_t>{0, 0, -1, -1});
  CHECK(features.amplitude[0] == doctest::Approx(kPi / 6));

  // Amplitude weighting: the fold is 0.3 radians above T = 0.1 (at least 2 T), so both hinge
  // vertices take the largest weight.
  options.feature_weighting = FeatureWeighting::amplitude;
  const MotionFeatures amplitude = features_of(mesh, options);
  CHECK(amplitude.connected == std::vector<uint8_t>{1, 0, 0, 0, 0});
  CHECK(amplitude.vertex_weights == std::vector<float>{4, 4, 1, 1});
  options.feature_threshold = kPi / 8;  // a = 4/3 T: a third of the way to the largest weight
  CHECK(features_of(mesh, options).vertex_weights[0] == doctest::Approx(1.0 + 3.0 / 3.0));
}

TEST_CASE("the amplitude is the range of the dihedral angle over all frames, whatever the frame rate") {
  // The hinge folds up by 30 degrees and back down to -10 over 9 frames: g is the largest step
  // between neighbouring frames and depends on the sampling, the amplitude (40 degrees) does not.
  for (int frame_count : {3, 9}) {
    OwnedAnimatedMesh mesh;
    mesh.faces = {0, 1, 2, 1, 0, 3};
    mesh.frame_count = size_t(2 * frame_count - 1);
    mesh.vertex_count = 4;
    for (int f = 0; f < 2 * frame_count - 1; ++f) {
      const double t = double(f) / (frame_count - 1);  // 0 .. 2
      const double fold = t <= 1.0 ? t * kPi / 6 : kPi / 6 - (t - 1.0) * (2 * kPi / 9);
      mesh.frames.insert(mesh.frames.end(), {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, float(-std::cos(fold)),
                                             float(std::sin(fold))});
    }
    MotionFeatureOptions options;
    options.boundary_is_feature = false;
    options.feature_threshold = 0.1;
    const MotionFeatures features = features_of(mesh, options);
    CHECK(features.amplitude[0] == doctest::Approx(kPi / 6 + kPi / 18).epsilon(1e-5));
    CHECK(features.angle_change[0] == doctest::Approx(2 * kPi / 9 / (frame_count - 1)).epsilon(1e-5));
  }
}

TEST_CASE("amplitude weighting finds nothing in noise that the paper turns into one huge feature") {
  // A closed sphere that only jitters: every vertex moves by up to 1% of the radius between
  // frames, as a capture's reconstruction noise does.
  const OwnedAnimatedMesh mesh = animlod::testing::jittering_sphere(16, 24, 12, 0.01f);
  MotionFeatureOptions options;
  options.feature_weighting = FeatureWeighting::paper;
  const MotionFeatures paper = features_of(mesh, options);
  int32_t largest = 0;
  for (int32_t size : paper.feature_sizes) largest = std::max(largest, size);
  CHECK(largest > 50);  // the mean of noisy g_i sits inside the noise: features everywhere
  options.feature_weighting = FeatureWeighting::amplitude;
  const MotionFeatures amplitude = features_of(mesh, options);
  CHECK(amplitude.feature_sizes.empty());
  for (float w : amplitude.vertex_weights) CHECK(w == 1.0f);
}

TEST_CASE("amplitude weights are bounded by max_feature_weight and need a threshold above the noise") {
  const OwnedAnimatedMesh mesh = animlod::testing::bending_tube(21, 12, 5, 1.2);
  MotionFeatureOptions options;
  options.max_feature_weight = 2.5;
  const MotionFeatures features = features_of(mesh, options);
  REQUIRE_FALSE(features.feature_sizes.empty());
  float largest = 0.0f;
  for (float w : features.vertex_weights) largest = std::max(largest, w);
  CHECK(largest == 2.5f);
  CHECK(features.threshold >= options.min_angle_change);
  options.max_feature_weight = 0.5;
  MotionFeatures rejected;
  CHECK(animlod::compute_motion_features(mesh.view(), options, rejected).message ==
        "motion features: max_feature_weight must be finite and >= 1");
  options.max_feature_weight = 4.0;
  options.noise_mads = -1.0;
  CHECK(animlod::compute_motion_features(mesh.view(), options, rejected).message ==
        "motion features: noise_mads must be finite and >= 0");
}

TEST_CASE("a rigidly translating mesh has no motion features") {
  OwnedAnimatedMesh mesh = animlod::testing::bending_tube(10, 12, 1, 0.0);
  const std::vector<float> first = mesh.frames;
  for (int f = 1; f < 6; ++f)
    for (size_t i = 0; i < first.size(); ++i) mesh.frames.push_back(first[i] + (i % 3 == 0 ? 0.37f * f : 0.0f));
  mesh.frame_count = 6;
  MotionFeatureOptions options;
  options.boundary_is_feature = false;
  const MotionFeatures features = features_of(mesh, options);
  CHECK(features.feature_sizes.empty());
  for (float w : features.vertex_weights) CHECK(w == 1.0f);

  // With the paper's boundary rule the two open ends are features of 12 vertices each.
  options.boundary_is_feature = true;
  options.feature_weighting = FeatureWeighting::paper;
  const MotionFeatures with_boundary = features_of(mesh, options);
  CHECK(with_boundary.feature_sizes == std::vector<int32_t>{12, 12});
  CHECK(with_boundary.vertex_weights[0] == 12.0f);
  CHECK(with_boundary.vertex_weights[12] == 1.0f);
  // The amplitude weighting reports them as features too but gives them no weight.
  options.feature_weighting = FeatureWeighting::amplitude;
  const MotionFeatures amplitude = features_of(mesh, options);
  CHECK(amplitude.feature_sizes == std::vector<int32_t>{12, 12});
  for (float w : amplitude.vertex_weights) CHECK(w == 1.0f);
}

TEST_CASE("a bending tube has its motion feature at the elbow") {
  const int rings = 21, segments = 12;
  const OwnedAnimatedMesh mesh = animlod::testing::bending_tube(rings, segments, 5, 1.2);
  MotionFeatureOptions options;
  options.boundary_is_feature = false;
  options.feature_weighting = FeatureWeighting::paper;
  const MotionFeatures features = features_of(mesh, options);
  // The elbow's two kinks (rings 9 and 11, where the blend zone starts and ends) bend most.
  REQUIRE_FALSE(features.feature_sizes.empty());
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    const double x = -1.0 + 2.0 * double(v / segments) / (rings - 1);  // rest position along the tube
    if (std::fabs(x) > 0.35) CHECK(features.vertex_feature[v] == -1);
  }
  for (int ring : {9, 11}) {
    const int32_t feature = features.vertex_feature[ring * segments];
    REQUIRE(feature >= 0);
    CHECK(features.vertex_weights[ring * segments] == float(features.feature_sizes[feature]));
  }
  CHECK(features.threshold > 0.0);
}

TEST_CASE("mesh validation rejects sizes beyond int32 indices before reading any data") {
  // Regression: 3 * face and 3 * vertex were int32 products and wrapped for huge meshes. The
  // counts are checked first, so the one-vertex buffers are never read past.
  const float frames[3] = {0, 0, 0};
  const int32_t faces[3] = {0, 0, 0};
  animlod::AnimatedMeshView mesh{frames, faces, 1, 1, 1};
  SUBCASE("vertices") {
    mesh.vertex_count = size_t{1} << 31;
    CHECK(animlod::validate_animated_mesh(mesh).message ==
          "frames: 2147483648 vertices, more than int32 indices reach (2147483647)");
  }
  SUBCASE("faces") {
    mesh.face_count = 715827883;  // 3 M = 2^31 + 1
    CHECK(animlod::validate_animated_mesh(mesh).message ==
          "faces: 715827883 faces, more than int32 corner indices reach (3 M <= 2147483647)");
    MotionFeatures features;
    CHECK_FALSE(animlod::compute_motion_features(mesh, {}, features).ok);
  }
}
