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
// inverted by Eq. 7, when its area vanishes in every frame, or when in some frame it flips so
// that the moved corner passes the line of the opposite edge, within the face's plane, by more
// than fold_limit times that edge's length (0: any flip; infinity: Eq. 7 alone). The paper's
// weights w_t, w_t' do not depend on the frame, so they cannot change the sign of the sum and
// are left out.
bool face_keeps_orientation(const std::array<const float*, 3>& corners, int moved, const Eigen::Vector3d* placed,
                            size_t frame_count, double fold_limit);

}  // namespace animlod::detail
