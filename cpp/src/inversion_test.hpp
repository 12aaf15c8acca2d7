// Eq. 7 of Yang et al. 2019, the inversion test of a collapse over all frames: a face around
// the collapse is inverted when sum_f n(t^f) . n(t'^f) sqrt(A(t^f) A(t'^f) w_t w_t') < 0.
#pragma once

#include <array>
#include <cstddef>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace animlod::detail {

// One face that survives a collapse. corners[c] points at corner c's positions in every frame,
// (F, 3) floats; corner `moved` goes to placed[f] in frame f. Returns false when the face is
// inverted by Eq. 7, when its area vanishes in every frame, or (strict) when it flips in any
// single frame. The paper's weights w_t, w_t' do not depend on the frame, so they cannot change
// the sign of the sum and are left out.
bool face_keeps_orientation(const std::array<const float*, 3>& corners, int moved, const Eigen::Vector3d* placed,
                            size_t frame_count, bool strict);

}  // namespace animlod::detail
