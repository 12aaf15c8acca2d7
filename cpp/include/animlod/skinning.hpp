// Linear blend skinning (LBS): bake a skinned mesh and a motion into per-frame positions.
#pragma once

#include <cstddef>
#include <cstdint>

#include "animlod/status.hpp"

namespace animlod {

// Non-owning views of the inputs of bake_lbs.
struct SkinningInput {
  const float* rest_positions = nullptr;  // (V, 3) bind-pose positions
  const int32_t* joints = nullptr;        // (V, K) joint index per influence
  const float* weights = nullptr;         // (V, K) influence weights (sum 1 per vertex)
  const float* skin_matrices = nullptr;   // (T, J, 16) world * inverse bind, column-major 4x4
  size_t vertex_count = 0;                // V
  size_t influence_count = 0;             // K
  size_t joint_count = 0;                 // J
  size_t frame_count = 0;                 // T
};

// Writes out_positions (T, V, 3): sum_k w_k * M[t, j_k] * rest. The caller owns
// out_positions, which must hold T * V * 3 floats.
// Errors: a joint index outside [0, J) or a non-finite weight (naming the vertex).
// Runs on thread_limit() threads (animlod/threads.hpp) when T * V is large enough.
Status bake_lbs(const SkinningInput& input, float* out_positions);

// Writes out_maxima (N, T): in each frame t, the largest distance between where skin `a` and
// skin others[n] put a vertex (the same V vertices and T frames; K and J may differ), without
// storing the frames: how far reduced skins stray from the input over a whole clip. Equal to the
// maxima over vertices of the distances between bake_lbs's outputs, bit for bit. On thread_limit() threads.
// Errors: V or T differ (naming the skin n), or bake_lbs's errors of a skin.
Status skin_distance_maxima(const SkinningInput& a, const SkinningInput* others, size_t other_count,
                            float* out_maxima);

}  // namespace animlod
