// Linear blend skinning: p_t = sum_k w_k M_{t, j_k} p_rest, accumulated in GLM.
#include "animlod/skinning.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "worker_threads.hpp"

#ifndef ANIMLOD_SKINNING_SSE2  // -DANIMLOD_SKINNING_SSE2=0 builds the portable code on x86 too
#if defined(__SSE2__) || defined(_M_X64)
#define ANIMLOD_SKINNING_SSE2 1
#else
#define ANIMLOD_SKINNING_SSE2 0
#endif
#endif
#if ANIMLOD_SKINNING_SSE2
#include <emmintrin.h>
#endif

namespace animlod {

namespace {

// Vertex-frames below which a thread costs more to start than it saves.
constexpr size_t kVertexFramesPerThread = 1 << 16;
// Vertices of a block of skin_distance_maxima: their positions, joints and weights (44 bytes a
// vertex with 4 influences) of ten skins stay in a core's L2 cache beside their matrices: nine
// distinct skins of 175k vertices over 300 frames took 2.6-3.4 s so, 3.5-4.9 s frame by frame.
constexpr size_t kBlockVertices = 256;

Status validate(const SkinningInput& in) {
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

// Where skin `in` puts vertex v in frame t.
glm::vec3 skinned_vertex(const SkinningInput& in, size_t t, size_t v) {
  const float* frame_matrices = in.skin_matrices + t * in.joint_count * 16;
  const size_t k_count = in.influence_count;
#if ANIMLOD_SKINNING_SSE2
  // GLM's mat4 * vec4 in four lanes, in its order, (c0 x + c1 y) + (c2 z + c3 1): the same bits
  // as the GLM code below at twice its speed (GLM's own SIMD would change its types' alignment).
  const __m128 x = _mm_set1_ps(in.rest_positions[3 * v]), y = _mm_set1_ps(in.rest_positions[3 * v + 1]),
               z = _mm_set1_ps(in.rest_positions[3 * v + 2]);
  __m128 skinned = _mm_setzero_ps();
  for (size_t k = 0; k < k_count; ++k) {
    const float weight = in.weights[v * k_count + k];
    if (weight == 0.0f) continue;  // weights are sorted, but zero padding may sit anywhere
    const float* m = frame_matrices + 16 * in.joints[v * k_count + k];  // column-major
    const __m128 moved = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(m), x), _mm_mul_ps(_mm_loadu_ps(m + 4), y)),
                                    _mm_add_ps(_mm_mul_ps(_mm_loadu_ps(m + 8), z), _mm_loadu_ps(m + 12)));
    skinned = _mm_add_ps(skinned, _mm_mul_ps(_mm_set1_ps(weight), moved));
  }
  alignas(16) float lanes[4];
  _mm_store_ps(lanes, skinned);
  return {lanes[0], lanes[1], lanes[2]};
#else
  const glm::vec4 rest(in.rest_positions[3 * v], in.rest_positions[3 * v + 1], in.rest_positions[3 * v + 2], 1.0f);
  glm::vec4 skinned(0.0f);
  for (size_t k = 0; k < k_count; ++k) {
    const float weight = in.weights[v * k_count + k];
    if (weight == 0.0f) continue;  // weights are sorted, but zero padding may sit anywhere
    const glm::mat4 m = glm::make_mat4(frame_matrices + 16 * in.joints[v * k_count + k]);
    skinned += weight * (m * rest);
  }
  return glm::vec3(skinned);
#endif
}

size_t worker_count(const SkinningInput& in) {
  const size_t cores = thread_limit();
  return std::clamp<size_t>(in.frame_count * in.vertex_count / kVertexFramesPerThread, 1, cores);
}

}  // namespace

Status bake_lbs(const SkinningInput& in, float* out_positions) {
  if (Status status = validate(in); !status) return status;
  const size_t vertices = in.vertex_count;
  if (vertices == 0) return Status::success();  // (the ranges below divide by it)
  detail::run_in_ranges(in.frame_count * vertices, worker_count(in), [&](size_t begin, size_t end, size_t) {
    for (size_t i = begin, t = begin / vertices, v = begin % vertices; i < end; ++i) {  // i = t * V + v
      const glm::vec3 p = skinned_vertex(in, t, v);
      std::copy_n(&p.x, 3, out_positions + 3 * i);
      if (++v == vertices) v = 0, ++t;
    }
  });
  return Status::success();
}

Status skin_distance_maxima(const SkinningInput& a, const SkinningInput* others, size_t other_count,
                            float* out_maxima) {
  for (size_t i = 0; i < other_count; ++i)
    if (others[i].vertex_count != a.vertex_count || others[i].frame_count != a.frame_count)
      return Status::error("skin " + std::to_string(i) + ": " + std::to_string(others[i].vertex_count) +
                           " vertices and " + std::to_string(others[i].frame_count) + " frames, expected " +
                           std::to_string(a.vertex_count) + " and " + std::to_string(a.frame_count));
  if (Status status = validate(a); !status) return status;
  for (size_t i = 0; i < other_count; ++i)
    if (Status status = validate(others[i]); !status)
      return Status::error("skin " + std::to_string(i) + ": " + status.message);
  const size_t frames = a.frame_count;
  // Frames to each thread, so that a frame's maxima are its own thread's; vertices in blocks
  // whose data of every skin stays in cache while the thread's frames visit them; skin `a` once
  // per vertex-frame.
  const size_t workers = std::min(worker_count(a), frames);
  detail::run_in_ranges(frames, workers, [&](size_t first, size_t last, size_t) {
    for (size_t i = 0; i < other_count; ++i)
      std::fill(out_maxima + i * frames + first, out_maxima + i * frames + last, 0.0f);
    for (size_t begin = 0; begin < a.vertex_count; begin += kBlockVertices) {
      const size_t end = std::min(begin + kBlockVertices, a.vertex_count);
      for (size_t t = first; t < last; ++t)
        for (size_t v = begin; v < end; ++v) {
          const glm::vec3 p = skinned_vertex(a, t, v);
          for (size_t i = 0; i < other_count; ++i) {
            const glm::vec3 d = skinned_vertex(others[i], t, v) - p;
            const float distance = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
            float& maximum = out_maxima[i * frames + t];
            if (maximum == maximum && !(distance <= maximum)) maximum = distance;  // a NaN stays, as in numpy
          }
        }
    }
  });
  return Status::success();
}

}  // namespace animlod
