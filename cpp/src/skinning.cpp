// Linear blend skinning: p_t = sum_k w_k M_{t, j_k} p_rest, accumulated in GLM.
#include "animlod/skinning.hpp"

#include <cmath>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace animlod {

static Status validate(const SkinningInput& in) {
  const size_t k_count = in.influence_count;
  for (size_t v = 0; v < in.vertex_count; ++v) {
    for (size_t k = 0; k < k_count; ++k) {
      const int32_t joint = in.joints[v * k_count + k];
      const float weight = in.weights[v * k_count + k];
      if (joint < 0 || static_cast<size_t>(joint) >= in.joint_count)
        return Status::error("vertex " + std::to_string(v) + ": joint index " + std::to_string(joint) +
                             " outside [0, " + std::to_string(in.joint_count) + ")");
      if (!std::isfinite(weight))
        return Status::error("vertex " + std::to_string(v) + ": non-finite skin weight");
    }
  }
  return Status::success();
}

Status bake_lbs(const SkinningInput& in, float* out_positions) {
  if (Status status = validate(in); !status) return status;
  const size_t k_count = in.influence_count;
  for (size_t t = 0; t < in.frame_count; ++t) {
    const float* frame_matrices = in.skin_matrices + t * in.joint_count * 16;
    float* out = out_positions + t * in.vertex_count * 3;
    for (size_t v = 0; v < in.vertex_count; ++v) {
      const glm::vec4 rest(in.rest_positions[3 * v], in.rest_positions[3 * v + 1], in.rest_positions[3 * v + 2], 1.0f);
      glm::vec4 skinned(0.0f);
      for (size_t k = 0; k < k_count; ++k) {
        const float weight = in.weights[v * k_count + k];
        if (weight == 0.0f) continue;  // weights are sorted, but zero padding may sit anywhere
        const glm::mat4 m = glm::make_mat4(frame_matrices + 16 * in.joints[v * k_count + k]);
        skinned += weight * (m * rest);
      }
      out[3 * v] = skinned.x;
      out[3 * v + 1] = skinned.y;
      out[3 * v + 2] = skinned.z;
    }
  }
  return Status::success();
}

}  // namespace animlod
