// A non-owning view of a deforming mesh with fixed connectivity: the input of the AQEM
// simplifier and of motion-feature extraction.
#pragma once

#include <cstddef>
#include <cstdint>

namespace animlod {

struct AnimatedMeshView {
  const float* frames = nullptr;   // (F, V, 3) positions, frame after frame, asset units
  const int32_t* faces = nullptr;  // (M, 3) counter-clockwise triangles, indices in [0, V)
  size_t frame_count = 0;          // F
  size_t vertex_count = 0;         // V
  size_t face_count = 0;           // M
};

}  // namespace animlod
