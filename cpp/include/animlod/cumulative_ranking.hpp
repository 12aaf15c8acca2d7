// The `cumulative` joint ranking of motion analysis (python/animlod/motion_lod/ranking.py): Eq. 3's
// question (seeds/000, Section 4) asked of the whole figure and asked again after each freeze.
// The next joint to freeze is the one whose freeze, with every joint chosen before it frozen,
// moves the figure's points least from their original positions, summed over points and frames.
#pragma once

#include <cstddef>
#include <cstdint>

#include "animlod/status.hpp"

namespace animlod {

// Freezing joint j replaces its local transform by its key frame's, which moves j and every point
// below it by one rigid transform per frame (the parent's world transform times the key local
// transform times the inverse of j's current world transform): no forward kinematics per
// candidate, and after a freeze only the frozen joint's ancestors and descendants are measured
// again.
//
// world: (n, J, 4, 4) row-major world transforms of the J joints at the n measured frames (the
// joints in parent-before-child order). key_local: (J, 4, 4) each joint's local transform at its
// key frame. parents: (J,) parent index, -1 for a root. candidates: (J,) 1 for joints that may
// freeze (never a root). Writes `scores` (J,): the step at which each candidate is frozen
// (0 first), infinity for the others; ties go to the lowest index. Errors (named by element): the
// checks of pose.hpp's validate_parents, a candidate root, a non-finite transform.
Status cumulative_freeze_steps(const double* world, const double* key_local, const int32_t* parents,
                               const uint8_t* candidates, size_t frame_count, size_t joint_count, double* scores);

}  // namespace animlod
