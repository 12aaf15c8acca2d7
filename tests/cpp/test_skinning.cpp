#include <doctest/doctest.h>

#include <vector>

#include "animlod/skinning.hpp"

namespace {
// Column-major 4x4 translation.
std::vector<float> translation(float x, float y, float z) {
  return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, x, y, z, 1};
}
}  // namespace

TEST_CASE("bake_lbs blends two translated joints by weight") {
  const std::vector<float> rest = {1, 2, 3};
  const std::vector<int32_t> joints = {0, 1};
  const std::vector<float> weights = {0.25f, 0.75f};
  std::vector<float> matrices = translation(4, 0, 0);
  const std::vector<float> second = translation(0, 8, 0);
  matrices.insert(matrices.end(), second.begin(), second.end());

  animlod::SkinningInput input;
  input.rest_positions = rest.data();
  input.joints = joints.data();
  input.weights = weights.data();
  input.skin_matrices = matrices.data();
  input.vertex_count = 1;
  input.influence_count = 2;
  input.joint_count = 2;
  input.frame_count = 1;
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
  animlod::SkinningInput input;
  input.rest_positions = rest.data();
  input.joints = joints.data();
  input.weights = weights.data();
  input.skin_matrices = matrices.data();
  input.vertex_count = 2;
  input.influence_count = 1;
  input.joint_count = 1;
  input.frame_count = 1;
  std::vector<float> out(6);
  const animlod::Status status = animlod::bake_lbs(input, out.data());
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("vertex 1") != std::string::npos);
}
