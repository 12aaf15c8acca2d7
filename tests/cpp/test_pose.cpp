#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "animlod/pose.hpp"

namespace {
using animlod::Interpolation;
using animlod::KeyframeTrack;
using animlod::RotationBlend;

KeyframeTrack track(const std::vector<float>& times, const std::vector<float>& values, size_t components,
                    Interpolation interpolation) {
  KeyframeTrack t;
  t.times = times.data();
  t.values = values.data();
  t.key_count = times.size();
  t.component_count = components;
  t.interpolation = interpolation;
  return t;
}

// (x, y, z, w) of a rotation by `angle` about z.
std::vector<float> about_z(float angle) { return {0.0f, 0.0f, std::sin(angle / 2), std::cos(angle / 2)}; }
}  // namespace

TEST_CASE("sample_track: LINEAR and STEP between and outside the keys") {
  const std::vector<float> times = {1.0f, 2.0f, 4.0f};
  const std::vector<float> values = {0, 0, 0, 10, 20, 30, 30, 20, 10};
  float out[3];
  const KeyframeTrack linear = track(times, values, 3, Interpolation::linear);
  REQUIRE(animlod::validate_track(linear, false).ok);
  animlod::sample_track(linear, 1.5f, false, RotationBlend::slerp, out);
  CHECK(out[0] == doctest::Approx(5));
  CHECK(out[2] == doctest::Approx(15));
  animlod::sample_track(linear, 3.0f, false, RotationBlend::slerp, out);
  CHECK(out[0] == doctest::Approx(20));
  CHECK(out[1] == doctest::Approx(20));
  animlod::sample_track(linear, 0.0f, false, RotationBlend::slerp, out);  // before: first key
  CHECK(out[1] == doctest::Approx(0));
  animlod::sample_track(linear, 9.0f, false, RotationBlend::slerp, out);  // after: last key
  CHECK(out[0] == doctest::Approx(30));

  const KeyframeTrack step = track(times, values, 3, Interpolation::step);
  animlod::sample_track(step, 1.99f, false, RotationBlend::slerp, out);
  CHECK(out[0] == doctest::Approx(0));
  animlod::sample_track(step, 2.0f, false, RotationBlend::slerp, out);
  CHECK(out[0] == doctest::Approx(10));
}

TEST_CASE("sample_track: CUBICSPLINE reproduces a cubic through its tangents") {
  // p(t) = t^3 on keys 0, 1, 3: value t^3, tangent 3 t^2 (in = out).
  const std::vector<float> times = {0.0f, 1.0f, 3.0f};
  std::vector<float> values;
  for (float t : times) {
    const float slope = 3 * t * t;
    values.insert(values.end(), {slope, t * t * t, slope});
  }
  const KeyframeTrack cubic = track(times, values, 1, Interpolation::cubic_spline);
  REQUIRE(animlod::validate_track(cubic, false).ok);
  for (float t : {0.25f, 0.5f, 1.5f, 2.2f, 2.9f}) {
    float out;
    animlod::sample_track(cubic, t, false, RotationBlend::slerp, &out);
    CHECK(out == doctest::Approx(t * t * t).epsilon(1e-5));
  }
}

TEST_CASE("sample_track: slerp halves the angle, takes the short way, and nlerp stays close") {
  const std::vector<float> times = {0.0f, 1.0f};
  std::vector<float> values = about_z(0.0f);
  const std::vector<float> end = about_z(1.5f);
  values.insert(values.end(), end.begin(), end.end());
  const KeyframeTrack rotation = track(times, values, 4, Interpolation::linear);
  float q[4];
  animlod::sample_track(rotation, 0.5f, true, RotationBlend::slerp, q);
  CHECK(q[2] == doctest::Approx(std::sin(0.375)));
  CHECK(q[3] == doctest::Approx(std::cos(0.375)));
  animlod::sample_track(rotation, 0.25f, true, RotationBlend::slerp, q);
  CHECK(2 * std::atan2(q[2], q[3]) == doctest::Approx(0.375));

  // The second key negated is the same rotation: the blend must not go the long way round.
  std::vector<float> flipped = values;
  for (int i = 4; i < 8; ++i) flipped[i] = -flipped[i];
  animlod::sample_track(track(times, flipped, 4, Interpolation::linear), 0.25f, true, RotationBlend::slerp, q);
  CHECK(2 * std::atan2(q[2], q[3]) == doctest::Approx(0.375));

  // Keys 10 degrees apart: nlerp within 1e-4 radians of slerp everywhere.
  std::vector<float> near = about_z(0.0f);
  const std::vector<float> ten = about_z(10.0f * 3.14159265f / 180.0f);
  near.insert(near.end(), ten.begin(), ten.end());
  const KeyframeTrack close = track(times, near, 4, Interpolation::linear);
  double worst = 0.0;
  for (float s = 0.0f; s <= 1.0f; s += 0.05f) {
    float a[4], b[4];
    animlod::sample_track(close, s, true, RotationBlend::slerp, a);
    animlod::sample_track(close, s, true, RotationBlend::nlerp, b);
    worst = std::max(worst, std::abs(2.0 * std::atan2(a[2], a[3]) - 2.0 * std::atan2(b[2], b[3])));
  }
  CHECK(worst > 0.0);
  CHECK(worst < 1e-4);
}

TEST_CASE("validate_track and validate_clip name the key and the channel") {
  const std::vector<float> times = {0.0f, 1.0f, 1.0f};
  const std::vector<float> values(9, 0.0f);
  animlod::Status status = animlod::validate_track(track(times, values, 3, Interpolation::linear), false);
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("key 2") != std::string::npos);

  const std::vector<float> one = {0.0f};
  const std::vector<float> zero(4, 0.0f);
  status = animlod::validate_track(track(one, zero, 4, Interpolation::linear), true);
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("zero-length") != std::string::npos);

  const std::vector<float> unit = about_z(0.0f);
  animlod::ClipChannel channels[2];
  channels[0].track = track(one, unit, 4, Interpolation::linear);
  channels[0].joint = 0;
  channels[1].track = track(one, unit, 4, Interpolation::linear);
  channels[1].joint = 7;
  status = animlod::validate_clip({channels, 2}, 3);
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("channel 1") != std::string::npos);
  channels[1].joint = 2;
  channels[1].path = animlod::ChannelPath::translation;  // 4 components for a translation
  status = animlod::validate_clip({channels, 2}, 3);
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("expected 3") != std::string::npos);
}

TEST_CASE("forward_kinematics and skin_palette on a bent two-bone arm") {
  // Joint 0 at (0, 1, 0) turned 90 degrees about z; joint 1 one unit along its parent's x.
  const std::vector<int32_t> parents = {-1, 0, 1};
  std::vector<float> translations = {0, 1, 0, 1, 0, 0, 2, 0, 0};
  std::vector<float> rotations = about_z(1.5707963f);
  const std::vector<float> identity = about_z(0.0f);
  for (int i = 0; i < 2; ++i) rotations.insert(rotations.end(), identity.begin(), identity.end());
  std::vector<float> scales = {1, 1, 1, 2, 2, 2, 1, 1, 1};  // joint 1 scales what hangs below it
  animlod::LocalPose pose{translations.data(), rotations.data(), scales.data(), 3};
  std::vector<float> world(3 * 16);
  REQUIRE(animlod::forward_kinematics(parents.data(), pose, world.data()).ok);
  // Joint 1: (0, 1, 0) + R(90) (1, 0, 0) = (0, 2, 0). Joint 2: + R(90) S(2) (2, 0, 0) = (0, 6, 0).
  CHECK(world[16 + 12] == doctest::Approx(0).epsilon(1e-6));
  CHECK(world[16 + 13] == doctest::Approx(2));
  CHECK(world[32 + 13] == doctest::Approx(6));

  // Palette of a skin over joints 2 and 0 (a subset in another order), inverse bind = translate(-1, 0, 0).
  const std::vector<int32_t> nodes = {2, 0};
  std::vector<float> inverse_bind(32, 0.0f);
  for (int s = 0; s < 2; ++s) {
    for (int d = 0; d < 4; ++d) inverse_bind[16 * s + 5 * d] = 1.0f;
    inverse_bind[16 * s + 12] = -1.0f;
  }
  std::vector<float> palette(32);
  animlod::skin_palette(world.data(), nodes.data(), inverse_bind.data(), 2, palette.data());
  // Skin joint 1 follows node 0: R(90) moves x by -1 -> y by -1, then (0, 1, 0): (0, 0, 0).
  CHECK(palette[16 + 12] == doctest::Approx(0).epsilon(1e-6));
  CHECK(palette[16 + 13] == doctest::Approx(0).epsilon(1e-6));
  // Skin joint 0 follows node 2 (scaled by 2): (0, 6, 0) + R(90) 2 (-1, 0, 0) = (0, 4, 0).
  CHECK(palette[13] == doctest::Approx(4));

  const std::vector<int32_t> bad = {-1, 2, 0};
  const animlod::Status status = animlod::forward_kinematics(bad.data(), pose, world.data());
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("joint 1") != std::string::npos);
}

TEST_CASE("clip_forward_kinematics chains double transforms frame by frame") {
  // Frame 0: joint 0 at (0, 1, 0) turned 90 degrees about z, joint 1 one unit along its x, joint
  // 2 two units further; frame 1: no turn.
  const std::vector<int32_t> parents = {-1, 0, 1};
  const double half = std::sqrt(0.5);
  const std::vector<double> translations = {0, 1, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 0, 0, 2, 0, 0};
  std::vector<double> rotations(2 * 3 * 4, 0.0);
  for (int k = 0; k < 6; ++k) rotations[4 * k + 3] = 1.0;
  rotations[2] = rotations[3] = half;  // frame 0, joint 0: 90 degrees about z
  std::vector<double> world(2 * 3 * 16);
  REQUIRE(animlod::clip_forward_kinematics(parents.data(), 3, translations.data(), rotations.data(), 2,
                                           world.data()).ok);
  // Row-major: the translation is the last column. Frame 0, joint 2: (0, 1, 0) + R(90) (3, 0, 0).
  CHECK(world[32 + 3] == doctest::Approx(0.0).epsilon(1e-15));
  CHECK(world[32 + 7] == doctest::Approx(4.0).epsilon(1e-15));
  CHECK(world[32 + 1] == doctest::Approx(-1.0).epsilon(1e-15));  // x turned onto y: R[0][1] = -1
  CHECK(world[48 + 32 + 3] == doctest::Approx(3.0).epsilon(1e-15));  // frame 1, joint 2: (3, 1, 0)
  CHECK(world[48 + 32 + 7] == doctest::Approx(1.0).epsilon(1e-15));
  CHECK(world[48 + 32 + 15] == 1.0);

  rotations[4 * 4 + 1] = NAN;  // frame 1, joint 1
  const animlod::Status status =
      animlod::clip_forward_kinematics(parents.data(), 3, translations.data(), rotations.data(), 2, world.data());
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("frame 1, joint 1") != std::string::npos);
  const std::vector<int32_t> bad = {-1, 2, 0};
  CHECK_FALSE(animlod::clip_forward_kinematics(bad.data(), 3, translations.data(), rotations.data(), 2,
                                               world.data()).ok);
}

TEST_CASE("quaternions_from_matrices inverts clip_forward_kinematics' rotations, w >= 0") {
  // Four turns, each making a different diagonal combination the largest (Shepperd's choice):
  // none (w), a half turn about x (x), a quarter turn about -y (y ties w: the first), a half turn
  // about z (z).
  const double h = std::sqrt(0.5);
  const std::vector<double> quaternions = {0, 0, 0, 1, 1, 0, 0, 0, 0, h, 0, -h, 0, 0, 1, 0};
  const std::vector<int32_t> parents = {-1, -1, -1, -1};
  const std::vector<double> translations(12, 0.0);
  std::vector<double> world(4 * 16), rotations_3x3(4 * 9), back(4 * 4);
  REQUIRE(animlod::clip_forward_kinematics(parents.data(), 4, translations.data(), quaternions.data(), 1,
                                           world.data()).ok);
  for (int j = 0; j < 4; ++j)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rotations_3x3[9 * j + 3 * r + c] = world[16 * j + 4 * r + c];
  animlod::quaternions_from_matrices(rotations_3x3.data(), 4, back.data());
  for (int j = 0; j < 4; ++j) {
    const double sign = quaternions[4 * j + 3] < 0.0 ? -1.0 : 1.0;  // q and -q are one rotation
    for (int k = 0; k < 4; ++k) CHECK(back[4 * j + k] == doctest::Approx(sign * quaternions[4 * j + k]).epsilon(1e-15));
    CHECK(back[4 * j + 3] >= 0.0);
  }
}

TEST_CASE("sample_clip writes only the animated joints and properties") {
  const std::vector<float> times = {0.0f, 1.0f};
  const std::vector<float> moves = {0, 0, 0, 4, 0, 0};
  animlod::ClipChannel channel;
  channel.track = track(times, moves, 3, Interpolation::linear);
  channel.joint = 1;
  channel.path = animlod::ChannelPath::translation;
  std::vector<float> translations = {7, 7, 7, 1, 1, 1};
  std::vector<float> rotations = {0, 0, 0, 1, 0, 0, 0, 1};
  animlod::LocalPose pose{translations.data(), rotations.data(), nullptr, 2};
  REQUIRE(animlod::validate_clip({&channel, 1}, 2).ok);
  animlod::sample_clip({&channel, 1}, 0.5f, RotationBlend::slerp, pose);
  CHECK(translations[0] == 7);
  CHECK(translations[3] == doctest::Approx(2));
  CHECK(translations[4] == doctest::Approx(0));
}

// Found by tests/fuzz/cpp/fuzz_pose.cpp (tests/fuzz/crashes/pose): a NaN time compared false
// everywhere and the LINEAR blend read the key after the last one.
TEST_CASE("sample_track: a NaN time gives the first key for every interpolation") {
  const std::vector<float> times = {1.0f, 2.0f, 4.0f};
  const std::vector<float> values = {1, 2, 3, 10, 20, 30, 30, 20, 10};
  std::vector<float> cubic_values;
  for (size_t k = 0; k < 3; ++k)
    cubic_values.insert(cubic_values.end(), {0, 0, 0, values[3 * k], values[3 * k + 1], values[3 * k + 2], 0, 0, 0});
  for (Interpolation interpolation : {Interpolation::linear, Interpolation::step, Interpolation::cubic_spline}) {
    const bool cubic = interpolation == Interpolation::cubic_spline;
    const KeyframeTrack t = track(times, cubic ? cubic_values : values, 3, interpolation);
    REQUIRE(animlod::validate_track(t, false).ok);
    float out[3] = {-1, -1, -1};
    animlod::sample_track(t, std::nanf(""), false, RotationBlend::slerp, out);
    CHECK(out[0] == 1.0f);
    CHECK(out[1] == 2.0f);
    CHECK(out[2] == 3.0f);
  }
}

// A CUBICSPLINE rotation between q and -q (the same rotation) with zero tangents passes through
// the zero quaternion halfway: the nearer key holds instead of a NaN.
TEST_CASE("sample_track: a CUBICSPLINE rotation through zero stays a unit quaternion") {
  const std::vector<float> times = {0.0f, 1.0f};
  const std::vector<float> values = {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0,    // key 0: in, value, out
                                     0, 0, 0, 0, 0, 0, 0, -1, 0, 0, 0, 0};  // key 1
  const KeyframeTrack t = track(times, values, 4, Interpolation::cubic_spline);
  REQUIRE(animlod::validate_track(t, true).ok);
  for (float time : {0.25f, 0.5f, 0.75f}) {
    float q[4];
    animlod::sample_track(t, time, true, RotationBlend::slerp, q);
    const float length = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    CHECK(length == doctest::Approx(1.0f));
  }
}
