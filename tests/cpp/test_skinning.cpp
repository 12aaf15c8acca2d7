#include <doctest/doctest.h>

#include <vector>

#include "animlod/skinning.hpp"

namespace {
// Column-major 4x4 translation.
std::vector<float> translation(float x, float y, float z) {
  return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, x, y, z, 1};
}

// One frame; the vectors must outlive the returned view.
animlod::SkinningInput one_frame(const std::vector<float>& rest, const std::vector<int32_t>& joints,
                                 const std::vector<float>& weights, const std::vector<float>& matrices) {
  animlod::SkinningInput input;
  input.rest_positions = rest.data();
  input.joints = joints.data();
  input.weights = weights.data();
  input.skin_matrices = matrices.data();
  input.vertex_count = rest.size() / 3;
  input.influence_count = joints.size() / input.vertex_count;
  input.joint_count = matrices.size() / 16;
  input.frame_count = 1;
  return input;
}
}  // namespace

TEST_CASE("bake_lbs blends two translated joints by weight") {
  const std::vector<float> rest = {1, 2, 3};
  std::vector<float> matrices = translation(4, 0, 0);
  const std::vector<float> second = translation(0, 8, 0);
  matrices.insert(matrices.end(), second.begin(), second.end());
  const std::vector<int32_t> joints = {0, 1};
  const std::vector<float> weights = {0.25f, 0.75f};
  const animlod::SkinningInput input = one_frame(rest, joints, weights, matrices);

  std::vector<float> out(3);
  REQUIRE(animlod::bake_lbs(input, out.data()).ok);
  CHECK(out[0] == doctest::Approx(1 + 0.25 * 4));
  CHECK(out[1] == doctest::Approx(2 + 0.75 * 8));
  CHECK(out[2] == doctest::Approx(3));
}

TEST_CASE("bake_lbs names the vertex with a joint index out of range") {
  const std::vector<float> rest = {0, 0, 0, 0, 0, 0};
  const std::vector<int32_t> joints = {0, 5};
  const std::vector<float> weights = {1, 1};
  const std::vector<float> matrices = translation(0, 0, 0);
  std::vector<float> out(6);
  const animlod::Status status = animlod::bake_lbs(one_frame(rest, joints, weights, matrices), out.data());
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("vertex 1") != std::string::npos);
}

TEST_CASE("bake_lbs and skin_distance_maxima take a skin without vertices") {
  const std::vector<float> matrices = translation(1, 2, 3);
  animlod::SkinningInput input;  // no vertices, one frame of one joint
  input.skin_matrices = matrices.data();
  input.influence_count = 4;
  input.joint_count = 1;
  input.frame_count = 1;
  CHECK(animlod::bake_lbs(input, nullptr).ok);
  float maximum = -1.0f;
  REQUIRE(animlod::skin_distance_maxima(input, &input, 1, &maximum).ok);
  CHECK(maximum == 0.0f);
}

TEST_CASE("skin_distance_maxima is each frame's largest distance between two skins") {
  const std::vector<float> rest = {0, 0, 0, 1, 0, 0};
  const std::vector<int32_t> joints = {0, 0};
  const std::vector<float> weights = {1, 1};
  std::vector<float> moved = translation(3, 4, 0);  // frame 0: 5 units off; frame 1: in place
  const std::vector<float> still = translation(0, 0, 0);
  moved.insert(moved.end(), still.begin(), still.end());
  std::vector<float> twice_still = still;
  twice_still.insert(twice_still.end(), still.begin(), still.end());
  animlod::SkinningInput a = one_frame(rest, joints, weights, twice_still), b = one_frame(rest, joints, weights, moved);
  a.frame_count = b.frame_count = 2;
  a.joint_count = b.joint_count = 1;
  std::vector<float> out(2, -1.0f);
  REQUIRE(animlod::skin_distance_maxima(a, &b, 1, out.data()).ok);
  CHECK(out[0] == doctest::Approx(5));
  CHECK(out[1] == 0.0f);

  b.frame_count = 1;
  const animlod::Status status = animlod::skin_distance_maxima(a, &b, 1, out.data());
  CHECK_FALSE(status.ok);
  CHECK(status.message == "skin 0: 2 vertices and 1 frames, expected 2 and 2");
}
