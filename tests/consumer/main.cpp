// Links the installed animlod::core and skins one vertex; exits non-zero if the result is wrong.
#include <animlod/skinning.hpp>

#include <cmath>
#include <cstdio>

int main() {
  const float rest[3] = {1.0f, 0.0f, 0.0f};
  const int32_t joints[1] = {0};
  const float weights[1] = {1.0f};
  // Column-major translation by (0, 2, 0).
  const float matrix[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 2, 0, 1};
  animlod::SkinningInput input;
  input.rest_positions = rest;
  input.joints = joints;
  input.weights = weights;
  input.skin_matrices = matrix;
  input.vertex_count = input.influence_count = input.joint_count = input.frame_count = 1;
  float out[3] = {};
  const animlod::Status status = animlod::bake_lbs(input, out);
  const bool correct = status.ok && std::fabs(out[0] - 1.0f) < 1e-6f && std::fabs(out[1] - 2.0f) < 1e-6f;
  std::printf("find_package(animlod) consumer: %s\n", correct ? "ok" : "FAILED");
  return correct ? 0 : 1;
}
