// How much noise a deforming mesh's frames carry, for the fold limit of AqemOptions: on a
// modelled or skinned mesh most edges ride on rigidly moving parts and keep their length to float
// rounding; a capture's reconstruction noise moves every edge's length from frame to frame.
#pragma once

#include "animlod/animated_mesh_view.hpp"

namespace animlod::detail {

// The 10th percentile, over the mesh's edges (at most 16,384 of them, evenly spread), of each
// edge length's standard deviation over the frames, relative to frame 0's bounding-box
// diagonal. 0 for one frame or a mesh of one point. Edges of rigid parts make it 0 up to float
// rounding (1e-7 for a Blender export, 3e-9 for Xbot's skinned clips); Gaussian noise of s per
// coordinate makes it about s (5e-4 of the diagonal: 5.3e-4 to 5.5e-4); a morph or a capture
// whose every edge deforms lies between (crane 8.5e-5, face-poses 1.7e-4).
double frame_noise_floor(const AnimatedMeshView& mesh);

}  // namespace animlod::detail
