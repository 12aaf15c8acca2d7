// Fuzz harness: pose.hpp, clip sampling, forward kinematics and the skinning palette, as the
// crowd and the glTF readers (sample_keyframes) call them. Input (little-endian):
//   u8  flags        bit 0: raw float32 numbers (NaN and inf possible), else int16 / 64;
//                    bit 1: nlerp (else slerp); bit 2: the pose has scales
//   u8  joints       J = 1 + value % 32
//   J parents        u8 each: 254 -> -2, 255 -> the joint itself (both invalid), else
//                    value % (j + 1) - 1 (topological)
//   u8  channels     value % 12; per channel:
//     u8 kind        bits 0-1: path (translation, rotation, scale; 3 -> translation), bits 2-3:
//                    interpolation (linear, step, cubic spline; 3 -> linear); bit 4: a wrong
//                    component count 1 + (value >> 5) % 4 instead of the path's
//     u16 joint      FuzzInput::index over J
//     u8 keys        N = value % 9
//     N times        the first a time (below), each next the previous plus u8 / 64 s (0: equal)
//     values         N * C numbers, 3 N C for the cubic spline
//   u8  samples      1 + value % 8 sample times; a time is a raw float32, or an int16 with
//                    -32768 -> NaN, 32767 -> +inf, 32766 -> -inf, else value / 64 s
//   J * 3 translations, J * 4 rotations, [J * 3 scales] of the rest pose
//   u8  skin joints  S = 1 + value % J; S joint nodes (value % J); S * 16 inverse bind entries
// Invariants: an error has a message; sampling a valid clip at any time (NaN included) writes
// only the joints it targets, and a rotation it writes is a unit quaternion; forward kinematics
// of a pose without scales, in int16 mode, is finite. The sampled poses (rotations normalised)
// as one clip through clip_forward_kinematics: refused exactly when a parent is invalid or a
// value is not finite; else last rows (0, 0, 0, 1), finite in int16 mode.
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "animlod/pose.hpp"
#include "fuzz_input.hpp"

namespace {

using animlod::fuzz::FuzzInput;

float sample_time(FuzzInput& in, bool raw) {
  if (raw) return in.take<float>();
  const int16_t value = in.take<int16_t>();
  if (value == std::numeric_limits<int16_t>::min()) return std::numeric_limits<float>::quiet_NaN();
  if (value == 32767) return std::numeric_limits<float>::infinity();
  if (value == 32766) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(value) / 64.0f;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzInput in(data, size);
  const uint8_t flags = in.take<uint8_t>();
  const bool raw = in.flag(flags, 0);
  const animlod::RotationBlend blend = in.flag(flags, 1) ? animlod::RotationBlend::nlerp : animlod::RotationBlend::slerp;
  const bool with_scales = in.flag(flags, 2);
  const size_t joint_count = 1 + in.take<uint8_t>() % 32;
  std::vector<int32_t> parents(joint_count);
  for (size_t j = 0; j < joint_count; ++j) {
    const uint8_t value = in.take<uint8_t>();
    parents[j] = value == 254 ? -2 : value == 255 ? static_cast<int32_t>(j) : static_cast<int32_t>(value % (j + 1)) - 1;
  }

  const size_t channel_count = in.take<uint8_t>() % 12;
  std::vector<std::vector<float>> times(channel_count), values(channel_count);
  std::vector<animlod::ClipChannel> channels(channel_count);
  for (size_t c = 0; c < channel_count; ++c) {
    animlod::ClipChannel& channel = channels[c];
    const uint8_t kind = in.take<uint8_t>();
    channel.path = static_cast<animlod::ChannelPath>((kind & 3) % 3);
    channel.track.interpolation = static_cast<animlod::Interpolation>(((kind >> 2) & 3) % 3);
    channel.track.component_count = (kind & 0x10) ? 1 + (kind >> 5) % 4 : channel.path == animlod::ChannelPath::rotation ? 4 : 3;
    channel.joint = in.index(joint_count);
    const size_t keys = in.take<uint8_t>() % 9;
    times[c].resize(keys);
    for (size_t k = 0; k < keys; ++k)
      times[c][k] = k == 0 ? sample_time(in, raw) : times[c][k - 1] + in.take<uint8_t>() / 64.0f;
    const size_t per_key = channel.track.interpolation == animlod::Interpolation::cubic_spline ? 3 : 1;
    values[c].resize(keys * per_key * channel.track.component_count);
    for (float& value : values[c]) value = in.coordinate(raw);
    channel.track.times = times[c].data();
    channel.track.values = values[c].data();
    channel.track.key_count = keys;
  }
  std::vector<float> sample_times(1 + in.take<uint8_t>() % 8);
  for (float& time : sample_times) time = sample_time(in, raw);

  std::vector<float> rest_t(3 * joint_count), rest_r(4 * joint_count), rest_s(with_scales ? 3 * joint_count : 0);
  for (float& value : rest_t) value = in.coordinate(raw);
  for (float& value : rest_r) value = in.coordinate(raw);
  for (float& value : rest_s) value = in.coordinate(raw);
  const size_t skin_count = 1 + in.take<uint8_t>() % joint_count;
  std::vector<int32_t> joint_nodes(skin_count);
  for (int32_t& node : joint_nodes) node = static_cast<int32_t>(in.take<uint8_t>() % joint_count);
  std::vector<float> inverse_bind(16 * skin_count);
  for (float& value : inverse_bind) value = in.coordinate(raw);

  // Every track alone, then the clip.
  for (const animlod::ClipChannel& channel : channels) {
    const bool rotation = channel.path == animlod::ChannelPath::rotation;
    const animlod::Status status = animlod::validate_track(channel.track, rotation);
    if (!status) {
      ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
      continue;
    }
    float out[4];
    for (float time : sample_times) {
      animlod::sample_track(channel.track, time, rotation, blend, out);
      if (rotation && channel.track.component_count == 4 && !raw) {
        const double length = std::sqrt(double(out[0]) * out[0] + double(out[1]) * out[1] + double(out[2]) * out[2] +
                                        double(out[3]) * out[3]);
        ANIMLOD_FUZZ_REQUIRE(std::fabs(length - 1.0) < 1e-3);
      }
    }
  }
  const animlod::ClipView clip{channels.data(), channels.size()};
  const animlod::Status clip_status = animlod::validate_clip(clip, joint_count);
  if (!clip_status) ANIMLOD_FUZZ_REQUIRE(!clip_status.message.empty());

  std::vector<float> world(16 * joint_count), palette(16 * skin_count);
  // The sampled poses as a clip in double, rotations normalised as Motion does, for
  // clip_forward_kinematics: every sample time a frame.
  std::vector<double> clip_t, clip_r;
  for (float time : sample_times) {
    std::vector<float> t = rest_t, r = rest_r, s = rest_s;
    const animlod::LocalPose pose{t.data(), r.data(), with_scales ? s.data() : nullptr, joint_count};
    if (clip_status) {
      animlod::sample_clip(clip, time, blend, pose);
      // Joints no channel targets keep the rest pose.
      std::vector<bool> targeted(joint_count, false);
      for (const animlod::ClipChannel& channel : channels) targeted[static_cast<size_t>(channel.joint)] = true;
      for (size_t j = 0; j < joint_count; ++j)
        if (!targeted[j])
          for (int k = 0; k < 4; ++k)
            ANIMLOD_FUZZ_REQUIRE(std::memcmp(&r[4 * j + k], &rest_r[4 * j + k], sizeof(float)) == 0);
    }
    clip_t.insert(clip_t.end(), t.begin(), t.end());
    for (size_t j = 0; j < joint_count; ++j) {
      const float* q = &r[4 * j];
      const double length = std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2] + double(q[3]) * q[3]);
      for (int k = 0; k < 4; ++k) clip_r.push_back(length > 0.0 ? q[k] / length : q[k]);
    }
    const animlod::Status status = animlod::forward_kinematics(parents.data(), pose, world.data());
    if (!status) {
      ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
      continue;
    }
    // |translations| <= 512 and unit rotations over at most 32 joints: far inside float range.
    if (!raw && !with_scales) {
      bool finite_pose = true;
      for (float value : t) finite_pose = finite_pose && std::isfinite(value) && std::fabs(value) <= 512.0f;
      if (finite_pose)
        for (float value : world) ANIMLOD_FUZZ_REQUIRE(std::isfinite(value));
    }
    animlod::skin_palette(world.data(), joint_nodes.data(), inverse_bind.data(), skin_count, palette.data());
  }
  std::vector<double> clip_world(16 * clip_r.size() / 4);
  const animlod::Status clip_fk = animlod::clip_forward_kinematics(parents.data(), joint_count, clip_t.data(),
                                                                   clip_r.data(), sample_times.size(), clip_world.data());
  bool valid = animlod::validate_parents(parents.data(), joint_count).ok;
  for (double value : clip_t) valid = valid && std::isfinite(value);
  for (double value : clip_r) valid = valid && std::isfinite(value);
  ANIMLOD_FUZZ_REQUIRE(clip_fk.ok == valid);
  if (!clip_fk) ANIMLOD_FUZZ_REQUIRE(!clip_fk.message.empty());
  // Last rows (0, 0, 0, 1); unit rotations and translations of at most 512 (int16 mode): finite.
  for (size_t i = 0; clip_fk && i < clip_world.size(); ++i) {
    if (!raw) ANIMLOD_FUZZ_REQUIRE(std::isfinite(clip_world[i]));
    if (i % 16 >= 12) ANIMLOD_FUZZ_REQUIRE(clip_world[i] == (i % 16 == 15 ? 1.0 : 0.0));
  }
  return 0;
}
