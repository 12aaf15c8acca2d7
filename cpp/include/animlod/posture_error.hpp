// The posture error of motion analysis (seeds/000, Section 4, Eq. 1): how far each bone's
// direction at one frame lies from its direction at every other frame, as an arc length.
// python/animlod/motion_lod/analysis.py builds the bone directions and turns the row sums into
// key frames (Eq. 2) and joint importance (Eq. 3).
#pragma once

#include <cstddef>

#include "animlod/status.hpp"

namespace animlod {

// For B bones over n frames, given each bone's direction `directions` (n, B, 3), unit or zero
// vectors, and its length `radii` (n, B), writes `out` (B, n):
//   out[c, a] = sum_b (r_c(a) + r_c(b)) / 2 * theta_c(a, b),
// theta_c(a, b) the angle between the bone's directions at frames a and b (Kahan's
// 2 atan2(|u - v|, |u + v|), accurate near 0 and pi; a zero vector, a bone of zero length in
// that frame, is at a right angle to any direction). These are the rows of Eq. 1's n x n table
// before the division by 2 pi r_max, one bone at a time (the paper sums them over a joint's
// child bones); the table itself is never stored. A bone whose direction never changes gets
// exact zeros. `threads` share the bones (0: thread_limit(), animlod/threads.hpp); the result does not
// depend on it. Errors: a non-finite direction or radius, naming the frame and the bone.
Status posture_error_row_sums(const double* directions, const double* radii, size_t frame_count, size_t bone_count,
                              unsigned threads, double* out);

}  // namespace animlod
