// Keyframe sampling (glTF 2.0 specification, Appendix C "Animation Sampler Interpolation
// Modes"), forward kinematics and the skinning palette (pose.hpp). The CPU animation step of the
// motion LoD paper's crowd pipeline (seeds/000, Section 3, Fig. 2).
#include "animlod/pose.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace animlod {

namespace {

const char* path_name(ChannelPath path) {
  switch (path) {
    case ChannelPath::translation: return "translation";
    case ChannelPath::rotation: return "rotation";
    case ChannelPath::scale: return "scale";
  }
  return "?";
}

// Stride in floats between two keys' values and offset of the value inside a key.
size_t key_stride(const KeyframeTrack& track) {
  return track.interpolation == Interpolation::cubic_spline ? 3 * track.component_count : track.component_count;
}
size_t value_offset(const KeyframeTrack& track) {
  return track.interpolation == Interpolation::cubic_spline ? track.component_count : 0;
}

// Normalises a quaternion of 4 floats in place (double inside, so that a float quaternion of
// length 1 +- 1e-7 comes back within rounding of unit length).
void normalize4(float* q) {
  const double length = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
  for (int i = 0; i < 4; ++i) q[i] = static_cast<float>(q[i] / length);
}

// Shortest-arc blend of unit quaternions a and b at s in [0, 1]. Slerp weights are computed in
// double: acos of a dot product near 1 loses most of its digits in float.
void blend_quaternions(const float* a, const float* b, double s, RotationBlend blend, float* out) {
  double dot = 0.0;
  for (int i = 0; i < 4; ++i) dot += double(a[i]) * b[i];
  const double sign = dot < 0.0 ? -1.0 : 1.0;
  dot = std::min(std::abs(dot), 1.0);
  double wa = 1.0 - s, wb = s;
  if (blend == RotationBlend::slerp) {
    const double theta = std::acos(dot);
    const double sin_theta = std::sin(theta);
    if (sin_theta >= 1e-8) {
      wa = std::sin((1.0 - s) * theta) / sin_theta;
      wb = std::sin(s * theta) / sin_theta;
    }
  }
  wb *= sign;
  for (int i = 0; i < 4; ++i) out[i] = static_cast<float>(wa * a[i] + wb * b[i]);
  normalize4(out);
}

// T * R * S of joint `joint`; `rotation` is the pose's quaternion already normalised.
glm::mat4 local_matrix(const LocalPose& pose, size_t joint, const glm::quat& rotation) {
  const float* t = pose.translations + 3 * joint;
  glm::mat4 m = glm::mat4_cast(rotation);
  if (pose.scales) {
    const float* s = pose.scales + 3 * joint;
    m[0] *= s[0];
    m[1] *= s[1];
    m[2] *= s[2];
  }
  m[3] = glm::vec4(t[0], t[1], t[2], 1.0f);
  return m;
}

}  // namespace

Status validate_track(const KeyframeTrack& track, bool rotation) {
  if (track.key_count == 0) return Status::error("track: has no key");
  if (track.component_count < 1 || track.component_count > 4)
    return Status::error("track: " + std::to_string(track.component_count) + " components per key, expected 1 to 4");
  if (!track.times || !track.values) return Status::error("track: times or values missing");
  for (size_t k = 0; k < track.key_count; ++k) {
    if (!std::isfinite(track.times[k]))
      return Status::error("track: key " + std::to_string(k) + " has a non-finite time");
    if (k > 0 && !(track.times[k] > track.times[k - 1]))
      return Status::error("track: key " + std::to_string(k) + " at " + std::to_string(track.times[k]) +
                           " s does not come after key " + std::to_string(k - 1) + " at " +
                           std::to_string(track.times[k - 1]) + " s (times must increase)");
  }
  const size_t stride = key_stride(track);
  for (size_t i = 0; i < track.key_count * stride; ++i) {
    if (!std::isfinite(track.values[i]))
      return Status::error("track: key " + std::to_string(i / stride) + " has a non-finite value");
  }
  if (rotation && track.component_count == 4) {
    for (size_t k = 0; k < track.key_count; ++k) {
      const float* q = track.values + k * stride + value_offset(track);
      if (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] < 1e-12f)
        return Status::error("track: key " + std::to_string(k) + " is a zero-length quaternion");
    }
  }
  return Status::success();
}

void sample_track(const KeyframeTrack& track, float time, bool rotation, RotationBlend blend, float* out) {
  assert(track.key_count >= 1 && track.component_count >= 1 && track.component_count <= 4);
  const size_t count = track.component_count, stride = key_stride(track), offset = value_offset(track);
  const bool quaternion = rotation && count == 4;
  const float* times = track.times;
  const size_t last = track.key_count - 1;
  auto value = [&](size_t key) { return track.values + key * stride + offset; };
  auto finish = [&](const float* v) {
    std::copy(v, v + count, out);
    if (quaternion) normalize4(out);
  };

  // The key interval [start, start + 1] holding `time` (the ends hold outside the keys). A NaN
  // time holds the first key: it compares false everywhere, so upper_bound below would give the
  // last key as `start` and read past the end (tests/fuzz/crashes/pose).
  if (last == 0 || !(time > times[0])) return finish(value(0));
  if (time >= times[last]) return finish(value(last));
  const size_t start = static_cast<size_t>(std::upper_bound(times, times + track.key_count, time) - times) - 1;
  if (track.interpolation == Interpolation::step) return finish(value(start));

  const double span = double(times[start + 1]) - times[start];
  const double s = std::clamp((double(time) - times[start]) / span, 0.0, 1.0);
  const float* a = value(start);
  const float* b = value(start + 1);
  if (track.interpolation == Interpolation::linear) {
    if (quaternion) return blend_quaternions(a, b, s, blend, out);
    for (size_t c = 0; c < count; ++c) out[c] = static_cast<float>(a[c] + s * (double(b[c]) - a[c]));
    return;
  }
  // Cubic Hermite spline (Appendix C): p(s) = (2s^3 - 3s^2 + 1) v_k + (s^3 - 2s^2 + s) span b_k
  //   + (-2s^3 + 3s^2) v_k+1 + (s^3 - s^2) span a_k+1, with b_k the out-tangent of key k and
  // a_k+1 the in-tangent of key k+1.
  const float* out_tangent = a + count;          // key start: [in, value, out]
  const float* in_tangent = b - count;           // key start + 1
  const double s2 = s * s, s3 = s2 * s;
  const double h00 = 2 * s3 - 3 * s2 + 1, h10 = (s3 - 2 * s2 + s) * span;
  const double h01 = -2 * s3 + 3 * s2, h11 = (s3 - s2) * span;
  for (size_t c = 0; c < count; ++c)
    out[c] = static_cast<float>(h00 * a[c] + h10 * out_tangent[c] + h01 * b[c] + h11 * in_tangent[c]);
  if (quaternion) {
    // Keys q and -q (the same rotation) with small tangents blend through zero, and huge
    // tangents overflow: the nearer key holds instead of a NaN (tests/fuzz/crashes/pose).
    double length2 = 0.0;
    for (size_t c = 0; c < 4; ++c) length2 += double(out[c]) * out[c];
    if (!(length2 > 0.0) || !std::isfinite(length2)) return finish(s < 0.5 ? a : b);
    normalize4(out);
  }
}

Status validate_clip(const ClipView& clip, size_t joint_count) {
  if (clip.channel_count > 0 && !clip.channels) return Status::error("clip: channels missing");
  for (size_t i = 0; i < clip.channel_count; ++i) {
    const ClipChannel& channel = clip.channels[i];
    const std::string name = "clip channel " + std::to_string(i) + " (" + path_name(channel.path) + ")";
    if (channel.joint < 0 || static_cast<size_t>(channel.joint) >= joint_count)
      return Status::error(name + ": joint " + std::to_string(channel.joint) + " outside [0, " +
                           std::to_string(joint_count) + ")");
    const size_t expected = channel.path == ChannelPath::rotation ? 4 : 3;
    if (channel.track.component_count != expected)
      return Status::error(name + ": " + std::to_string(channel.track.component_count) + " components per key, expected " +
                           std::to_string(expected));
    const Status status = validate_track(channel.track, channel.path == ChannelPath::rotation);
    if (!status) return Status::error(name + ": " + status.message);
  }
  return Status::success();
}

void sample_clip(const ClipView& clip, float time, RotationBlend blend, const LocalPose& pose) {
  for (size_t i = 0; i < clip.channel_count; ++i) {
    const ClipChannel& channel = clip.channels[i];
    assert(channel.joint >= 0 && static_cast<size_t>(channel.joint) < pose.joint_count);
    const size_t joint = static_cast<size_t>(channel.joint);
    switch (channel.path) {
      case ChannelPath::translation:
        sample_track(channel.track, time, false, blend, pose.translations + 3 * joint);
        break;
      case ChannelPath::rotation:
        sample_track(channel.track, time, true, blend, pose.rotations + 4 * joint);
        break;
      case ChannelPath::scale:
        if (pose.scales) sample_track(channel.track, time, false, blend, pose.scales + 3 * joint);
        break;
    }
  }
}

Status validate_parents(const int32_t* parents, size_t joint_count) {
  if (joint_count > 0 && !parents) return Status::error("skeleton: parents missing");
  for (size_t j = 0; j < joint_count; ++j) {
    if (parents[j] < -1 || parents[j] >= static_cast<int32_t>(j))
      return Status::error("skeleton: joint " + std::to_string(j) + " has parent " + std::to_string(parents[j]) +
                           ", expected -1 or a joint before it (topological order)");
  }
  return Status::success();
}

Status forward_kinematics(const int32_t* parents, const LocalPose& pose, float* out_world) {
  Status status = validate_parents(parents, pose.joint_count);
  if (!status) return status;
  for (size_t j = 0; j < pose.joint_count; ++j) {
    const float* r = pose.rotations + 4 * j;
    const float length2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3];
    if (!std::isfinite(length2) || length2 < 1e-12f)
      return Status::error("pose: joint " + std::to_string(j) + " has a zero-length or non-finite rotation");
    const float inverse = 1.0f / std::sqrt(length2);
    const glm::quat rotation(r[3] * inverse, r[0] * inverse, r[1] * inverse, r[2] * inverse);  // (w, x, y, z)
    const glm::mat4 local = local_matrix(pose, j, rotation);
    const glm::mat4 world = parents[j] < 0 ? local : glm::make_mat4(out_world + 16 * parents[j]) * local;
    std::copy(glm::value_ptr(world), glm::value_ptr(world) + 16, out_world + 16 * j);
  }
  return Status::success();
}

Status clip_forward_kinematics(const int32_t* parents, size_t joint_count, const double* translations,
                               const double* rotations, size_t frame_count, double* out_world) {
  Status status = validate_parents(parents, joint_count);
  if (!status) return status;
  for (size_t f = 0; f < frame_count; ++f)
    for (size_t j = 0; j < joint_count; ++j) {
      const size_t k = f * joint_count + j;
      const double *t = translations + 3 * k, *q = rotations + 4 * k;
      double* world = out_world + 16 * k;
      if (!std::isfinite(t[0] + t[1] + t[2]) || !std::isfinite(q[0] + q[1] + q[2] + q[3]))
        return Status::error("frame " + std::to_string(f) + ", joint " + std::to_string(j) +
                             ": non-finite translation or rotation");
      const double x = q[0], y = q[1], z = q[2], w = q[3];
      const double local[12] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w),     2 * (x * z + y * w),     t[0],
                                2 * (x * y + z * w),     1 - 2 * (x * x + z * z), 2 * (y * z - x * w),     t[1],
                                2 * (x * z - y * w),     2 * (y * z + x * w),     1 - 2 * (x * x + y * y), t[2]};
      if (parents[j] < 0) {
        std::copy(local, local + 12, world);
      } else {  // the parent's rows times the local matrix (whose last row is 0 0 0 1)
        const double* parent = out_world + 16 * (f * joint_count + static_cast<size_t>(parents[j]));
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 4; ++c)
            world[4 * r + c] = parent[4 * r] * local[c] + parent[4 * r + 1] * local[4 + c] +
                               parent[4 * r + 2] * local[8 + c] + (c == 3 ? parent[4 * r + 3] : 0.0);
      }
      world[12] = world[13] = world[14] = 0.0;
      world[15] = 1.0;
    }
  return Status::success();
}

void quaternions_from_matrices(const double* matrices, size_t count, double* out_quaternions) {
  for (size_t i = 0; i < count; ++i) {
    const double* m = matrices + 9 * i;
    double* q = out_quaternions + 4 * i;
    const double m00 = m[0], m11 = m[4], m22 = m[8];
    const double candidates[4] = {1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22, 1 + m00 + m11 + m22};
    int choice = 0;  // the first largest; the first NaN, as numpy's argmax
    for (int k = 0; k < 4 && !std::isnan(candidates[choice]); ++k)
      if (std::isnan(candidates[k]) || candidates[k] > candidates[choice]) choice = k;
    const double s = std::sqrt(std::max(candidates[choice], 1e-300));
    const double d21 = m[7] - m[5], d02 = m[2] - m[6], d10 = m[3] - m[1];
    const double s01 = m[1] + m[3], s02 = m[2] + m[6], s12 = m[5] + m[7];
    const double rows[4][4] = {{s * s, s01, s02, d21}, {s01, s * s, s12, d02}, {s02, s12, s * s, d10}, {d21, d02, d10, s * s}};
    for (int k = 0; k < 4; ++k) q[k] = rows[choice][k] / (2.0 * s);
    if (q[3] < 0.0)
      for (int k = 0; k < 4; ++k) q[k] *= -1.0;
  }
}

void skin_palette(const float* world, const int32_t* joint_nodes, const float* inverse_bind, size_t skin_joint_count,
                  float* out_palette) {
  for (size_t s = 0; s < skin_joint_count; ++s) {
    const size_t node = joint_nodes ? static_cast<size_t>(joint_nodes[s]) : s;
    const glm::mat4 palette = glm::make_mat4(world + 16 * node) * glm::make_mat4(inverse_bind + 16 * s);
    std::copy(glm::value_ptr(palette), glm::value_ptr(palette) + 16, out_palette + 16 * s);
  }
}

}  // namespace animlod
