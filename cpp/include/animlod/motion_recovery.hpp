// A motion level's joint rotations recovered from re-fitted positions (seeds/000, end of Section
// 5.2: "the local transformation value of each joint is recovered from the optimisation result
// x_j(t) and the hierarchical information of each joint"): the per-frame part of
// python/animlod/motion_lod/skeleton_reduce.py's recover_motion, which prepares the level's
// skeleton and calls this for every frame at once.
#pragma once

#include <cstddef>
#include <cstdint>

#include "animlod/status.hpp"

namespace animlod {

// The level's skeleton as the recovery reads it. Joint j is aimed by the children
// aim_children[aim_offsets[j], aim_offsets[j + 1]): one child, the smallest rotation (swing)
// that turns it towards its re-fitted position; several (spanning a plane), the best-fit
// rotation (Kabsch) of all of them; none, no correction.
struct AimedSkeleton {
  const int32_t* parents = nullptr;       // (K,) -1 for a root, parents before children
  const uint8_t* translating = nullptr;   // (K,) 1: no fixed bone, placed by its own translation
  const int32_t* aim_offsets = nullptr;   // (K + 1,)
  const int32_t* aim_children = nullptr;  // (aim_offsets[K],) children of each joint, none translating
  size_t joint_count = 0;                 // K
};

// Per frame, in joint order: a root is placed at its target, any other joint by forward
// kinematics from its parent (a translating joint first takes the translation that puts it at
// its target); its world rotation
// starts from `original_world` (so a bone keeps its twist) and is corrected by the rotation that
// aims its children's offsets from where the joint was placed at their targets, so misfits do
// not pile up down a chain.
//
// original_world: (T, K, 4) unit quaternions (x, y, z, w), the original world rotations.
// targets: (T, K, 3) re-fitted positions (the root's is where it is placed).
// translations: (T, K, 3) the joints' offsets in their parents' frames; a translating joint's is
// replaced by the recovered one. out_world: (T, K, 4) recovered world rotations (not normalised
// again after the correction, as the quaternion products leave them).
// Errors (naming the element): the checks of pose.hpp's validate_parents, a child index out of
// range or not a child of its joint, a translating aim child, a non-finite input.
Status recover_world_rotations(const AimedSkeleton& skeleton, size_t frame_count, const double* original_world,
                               const double* targets, double* translations, double* out_world);

}  // namespace animlod
