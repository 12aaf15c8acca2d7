// Posing a skeleton at run time: a keyframe sampler with glTF 2.0's interpolations (LINEAR,
// STEP, CUBICSPLINE; Appendix C of the specification), clips of such tracks targeting joints,
// forward kinematics to world transforms and the skinning palette (world * inverse bind) that
// GPU skinning uploads. This is the CPU half of the crowd pipeline of the motion LoD paper
// (seeds/000, Section 3, Fig. 2: the CPU sends the joint transforms, the GPU skins).
//
// Conventions: quaternions (x, y, z, w); matrices 4x4 column-major (16 floats, GLM's layout);
// joints in topological order (parents[j] < j, -1 for a root); times in seconds; units the
// asset's. Inputs are non-owning views; the caller owns every output buffer.
#pragma once

#include <cstddef>
#include <cstdint>

#include "animlod/status.hpp"

namespace animlod {

enum class Interpolation : uint8_t {
  linear,        // lerp; slerp (or nlerp, see RotationBlend) for rotations
  step,          // the value of the last key at or before the time
  cubic_spline,  // cubic Hermite with the in/out tangents stored beside each key
};

// How LINEAR interpolates quaternions. glTF asks for slerp; nlerp (normalised lerp, shortest
// path) is cheaper and differs from slerp by under 1e-4 radians between keys 10 degrees apart.
enum class RotationBlend : uint8_t { slerp, nlerp };

// The keys of one animated property (a glTF animation sampler).
struct KeyframeTrack {
  const float* times = nullptr;   // (N,) seconds, strictly increasing, finite
  const float* values = nullptr;  // (N, C), or (N, 3, C) for cubic_spline: in-tangent, value,
                                  // out-tangent per key (tangents in units per second)
  size_t key_count = 0;           // N >= 1
  size_t component_count = 0;     // C in [1, 4]; 4 with rotation = true is an (x, y, z, w) quaternion
  Interpolation interpolation = Interpolation::linear;
};

// Checks a track once, before sampling it: N >= 1, C in [1, 4], finite strictly increasing times,
// finite values, and (for quaternion tracks, `rotation` true and C == 4) no zero-length key.
// Errors name the key.
Status validate_track(const KeyframeTrack& track, bool rotation);

// Writes the track's C components at `time` into out (C floats). Before the first key and after
// the last one the end keys hold; a NaN time gives the first key. With `rotation` (C == 4) LINEAR keys are blended along the
// shortest arc and the result of every interpolation is a unit quaternion. The track must have
// passed validate_track (not re-checked here, asserted in debug builds).
void sample_track(const KeyframeTrack& track, float time, bool rotation, RotationBlend blend, float* out);

// Which property of a joint a channel animates.
enum class ChannelPath : uint8_t { translation, rotation, scale };

struct ClipChannel {
  KeyframeTrack track;  // C = 3 for translation and scale, 4 for rotation
  int32_t joint = 0;    // index into the skeleton the clip poses
  ChannelPath path = ChannelPath::rotation;
};

// A clip: channels targeting the joints of one skeleton (a glTF animation restricted to a skin).
struct ClipView {
  const ClipChannel* channels = nullptr;  // (channel_count,)
  size_t channel_count = 0;
};

// Checks every channel of a clip (validate_track with the channel's path) and that it targets a
// joint in [0, joint_count) with the component count of its path. Errors name the channel.
Status validate_clip(const ClipView& clip, size_t joint_count);

// A local pose of J joints (non-owning, mutable): every joint's transform relative to its parent,
// T(translation) * R(rotation) * S(scale).
struct LocalPose {
  float* translations = nullptr;  // (J, 3)
  float* rotations = nullptr;     // (J, 4) unit quaternions (x, y, z, w)
  float* scales = nullptr;        // (J, 3), or null for unit scale everywhere
  size_t joint_count = 0;         // J
};

// Samples every channel of `clip` at `time` into `pose`; properties no channel animates keep the
// values the caller put there (the rest pose, typically). Scale channels are skipped when
// pose.scales is null. The clip must have passed validate_clip for pose.joint_count.
void sample_clip(const ClipView& clip, float time, RotationBlend blend, const LocalPose& pose);

// Checks a hierarchy: parents (J,) with -1 <= parents[j] < j (topological order, any number of
// roots). Errors name the joint.
Status validate_parents(const int32_t* parents, size_t joint_count);

// Forward kinematics: world (J, 16) column-major, world[j] = world[parents[j]] * local[j] with
// local[j] = T * R * S from the pose (world[j] = local[j] for a root). Rotations are normalised
// on the way. Errors: the checks of validate_parents, a non-finite or zero-length rotation
// (naming the joint); out_world is then left partially written.
Status forward_kinematics(const int32_t* parents, const LocalPose& pose, float* out_world);

// Forward kinematics of T frames in double precision, for motion processing (motion LoD's
// re-fit resolves 1e-13 of a figure, float 1e-7): world (T, J, 4, 4) row-major, acting on
// column vectors (numpy's layout), world[t, j] = world[t, parents[j]] * T(translation) *
// R(rotation) from translations (T, J, 3) and unit quaternions (x, y, z, w) (T, J, 4), used as
// given (a caller's rotations are already unit). Errors: the checks of validate_parents, a
// non-finite translation or rotation (naming the frame and the joint); out_world is then left
// partially written.
Status clip_forward_kinematics(const int32_t* parents, size_t joint_count, const double* translations,
                               const double* rotations, size_t frame_count, double* out_world);

// Unit quaternions (x, y, z, w) with w >= 0 of `count` rotation matrices (3 x 3 row-major),
// Shepperd's method: the largest of the four diagonal combinations sets the divisor. The same
// operations as python/animlod/rotations.py's from_matrix did in numpy, element for element.
void quaternions_from_matrices(const double* matrices, size_t count, double* out_quaternions);

// The skinning palette for S skin joints: out[s] = world[joint_nodes[s]] * inverse_bind[s]
// (column-major (S, 16) each). joint_nodes (S,) maps a skin joint to the posed node it follows
// (a glTF skin's joints may be a subset of a larger node tree); null means s -> s. The indices
// must lie in [0, J) of the world array (the caller's contract; asserted in debug builds).
void skin_palette(const float* world, const int32_t* joint_nodes, const float* inverse_bind, size_t skin_joint_count,
                  float* out_palette);

}  // namespace animlod
