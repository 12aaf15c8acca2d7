#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "animlod/motion_recovery.hpp"

namespace {

// Quaternion (x, y, z, w) of `angle` about the unit `axis`.
std::vector<double> about(double x, double y, double z, double angle) {
  const double s = std::sin(angle / 2);
  return {x * s, y * s, z * s, std::cos(angle / 2)};
}

// v rotated by the unit quaternion q.
void rotate(const double* q, const double* v, double* out) {
  const double t[3] = {2 * (q[1] * v[2] - q[2] * v[1]), 2 * (q[2] * v[0] - q[0] * v[2]), 2 * (q[0] * v[1] - q[1] * v[0])};
  const double c[3] = {q[1] * t[2] - q[2] * t[1], q[2] * t[0] - q[0] * t[2], q[0] * t[1] - q[1] * t[0]};
  for (int a = 0; a < 3; ++a) out[a] = v[a] + q[3] * t[a] + c[a];
}

// root (0) -> hand (1) -> fingers 2, 3 (spanning a plane: a best-fit rotation) and 1 -> thumb 4;
// 2 -> tip 5 (one child: a swing). Offsets in the parents' frames.
struct Hand {
  const int32_t parents[6] = {-1, 0, 1, 1, 1, 2};
  uint8_t translating[6] = {0, 0, 0, 0, 0, 0};
  const int32_t aim_offsets[7] = {0, 1, 4, 5, 5, 5, 5};
  const int32_t aim_children[5] = {1, 2, 3, 4, 5};
  const double offsets[6][3] = {{0, 0, 0}, {0, 1, 0}, {0.2, 0.5, 0}, {-0.2, 0.5, 0.1}, {0.3, 0.1, 0.2}, {0, 0.4, 0}};
  animlod::AimedSkeleton view() const { return {parents, translating, aim_offsets, aim_children, 6}; }
};

}  // namespace

TEST_CASE("recovered rotations put rigidly moved children back on their targets") {
  const Hand hand;
  // Targets: forward kinematics of other world rotations; the original world rotations (where
  // the recovery starts) are identities.
  const std::vector<std::vector<double>> world = {about(0, 0, 1, 0.3), about(1, 0, 0, -0.8), about(0, 1, 0, 0.5),
                                                  about(0, 0, 1, 0), about(0, 0, 1, 0), about(0, 0, 1, 0)};
  std::vector<double> targets(18, 0.0), translations(18), original(24, 0.0), out(24);
  for (int j = 0; j < 6; ++j) {
    original[4 * j + 3] = 1.0;
    for (int a = 0; a < 3; ++a) translations[3 * j + a] = hand.offsets[j][a];
    if (j == 0) continue;
    double moved[3];
    rotate(world[hand.parents[j]].data(), hand.offsets[j], moved);
    for (int a = 0; a < 3; ++a) targets[3 * j + a] = targets[3 * hand.parents[j] + a] + moved[a];
  }
  const animlod::Status status =
      animlod::recover_world_rotations(hand.view(), 1, original.data(), targets.data(), translations.data(), out.data());
  REQUIRE_MESSAGE(status.ok, status.message);
  // The hand (three children spanning space) and the finger (one child) turn exactly as the
  // targets did, up to the twist about the finger's bone, which the tip cannot see: check positions.
  for (int j : {0, 1}) {
    const double sign = out[4 * j + 3] * world[j][3] < 0 ? -1.0 : 1.0;
    for (int a = 0; a < 4; ++a) CHECK(sign * out[4 * j + a] == doctest::Approx(world[j][a]).epsilon(1e-12));
  }
  double tip[3];
  rotate(&out[4 * 2], hand.offsets[5], tip);
  for (int a = 0; a < 3; ++a) CHECK(targets[3 * 2 + a] + tip[a] == doctest::Approx(targets[3 * 5 + a]).epsilon(1e-12));
}

TEST_CASE("a translating joint takes the translation that puts it on its target") {
  Hand hand;
  hand.translating[4] = 1;  // the thumb slides: it no longer aims the hand, which keeps two fingers
  const int32_t aim_offsets[7] = {0, 1, 3, 4, 4, 4, 4};
  const int32_t aim_children[4] = {1, 2, 3, 5};
  const animlod::AimedSkeleton view{hand.parents, hand.translating, aim_offsets, aim_children, 6};
  std::vector<double> original(24, 0.0), translations(18), out(24);
  for (int j = 0; j < 6; ++j) {
    original[4 * j + 3] = 1.0;
    for (int a = 0; a < 3; ++a) translations[3 * j + a] = hand.offsets[j][a];
  }
  std::vector<double> targets = {0, 0, 0, 0, 1, 0, 0.2, 1.5, 0, -0.2, 1.5, 0.1, 2.0, 3.0, 4.0, 0.2, 1.9, 0};
  REQUIRE(animlod::recover_world_rotations(view, 1, original.data(), targets.data(), translations.data(), out.data()));
  // Nothing turned, so the thumb's offset is its target less the hand's position.
  CHECK(translations[12] == doctest::Approx(2.0));
  CHECK(translations[13] == doctest::Approx(2.0));
  CHECK(translations[14] == doctest::Approx(4.0));
  CHECK(out[4 * 1 + 3] == doctest::Approx(1.0));
}

TEST_CASE("a second root is placed at its target and aims its child there") {
  const int32_t parents[4] = {-1, 0, -1, 2};
  const uint8_t translating[4] = {0, 0, 0, 0};
  const int32_t aim_offsets[5] = {0, 1, 1, 2, 2};
  const int32_t aim_children[2] = {1, 3};
  const animlod::AimedSkeleton view{parents, translating, aim_offsets, aim_children, 4};
  std::vector<double> original(16, 0.0), out(16);
  for (int j = 0; j < 4; ++j) original[4 * j + 3] = 1.0;
  std::vector<double> translations = {0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1, 0};
  const std::vector<double> targets = {0, 0, 0, 0, 1, 0, 5, 0, 0, 6, 0, 0};  // the second arm points along x
  REQUIRE(animlod::recover_world_rotations(view, 1, original.data(), targets.data(), translations.data(), out.data()));
  double tip[3];
  rotate(&out[4 * 2], &translations[3 * 3], tip);
  CHECK(5.0 + tip[0] == doctest::Approx(6.0));
  CHECK(tip[1] == doctest::Approx(0.0).epsilon(1e-12));
  CHECK(out[4 * 0 + 3] == doctest::Approx(1.0));  // the first arm already points at its target
}

TEST_CASE("motion recovery names bad input") {
  Hand hand;
  std::vector<double> original(24, 0.0), targets(18, 0.0), translations(18, 0.0), out(24);
  for (int j = 0; j < 6; ++j) original[4 * j + 3] = 1.0;
  const auto run = [&](const animlod::AimedSkeleton& view) {
    return animlod::recover_world_rotations(view, 1, original.data(), targets.data(), translations.data(), out.data())
        .message;
  };
  const int32_t late[6] = {-1, 0, 1, 1, 5, 2};
  CHECK(run({late, hand.translating, hand.aim_offsets, hand.aim_children, 6}) ==
        "skeleton: joint 4 has parent 5, expected -1 or a joint before it (topological order)");
  const int32_t stranger[5] = {1, 2, 3, 5, 5};
  CHECK(run({hand.parents, hand.translating, hand.aim_offsets, stranger, 6}) ==
        "aim_children[3]: 5 is not a child of joint 1");
  hand.translating[2] = 1;
  CHECK(run(hand.view()) == "aim_children[1]: joint 2 translates: it cannot aim its parent");
  hand.translating[2] = 0;
  targets[3 * 4 + 1] = std::nan("");
  CHECK(run(hand.view()) == "targets[0, 4]: not finite");
}
