// Choosing K of F frames that cover a motion, for quadrics over long sequences.
#pragma once

#include <cstdint>
#include <vector>

#include "animlod/animated_mesh_view.hpp"

namespace animlod::detail {

// Farthest-point sampling of the poses: start from frame 0, then repeatedly add the frame
// whose smallest squared distance (summed over vertices) to the frames chosen so far is
// largest, ties to the earlier frame. Returns min(count, F) frame indices, ascending.
// Cost O(count * F * V), the distances on every core.
std::vector<int32_t> sample_frames(const AnimatedMeshView& mesh, size_t count);

}  // namespace animlod::detail
