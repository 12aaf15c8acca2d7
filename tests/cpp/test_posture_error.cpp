#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "animlod/posture_error.hpp"

namespace {

// Directions (n, B, 3) and radii (n, B) of B bones over n frames, filled per bone.
struct Bones {
  size_t frames, count;
  std::vector<double> directions, radii;
  Bones(size_t n, size_t b) : frames(n), count(b), directions(3 * n * b, 0.0), radii(n * b, 0.0) {}
  void set(size_t frame, size_t bone, double x, double y, double z, double radius) {
    double* d = &directions[3 * (frame * count + bone)];
    d[0] = x, d[1] = y, d[2] = z;
    radii[frame * count + bone] = radius;
  }
  std::vector<double> row_sums(unsigned threads) const {
    std::vector<double> out(count * frames, -1.0);
    const animlod::Status status =
        animlod::posture_error_row_sums(directions.data(), radii.data(), frames, count, threads, out.data());
    REQUIRE_MESSAGE(status.ok, status.message);
    return out;
  }
};

}  // namespace

TEST_CASE("posture error rows sum the arcs of a bone's turn (Eq. 1)") {
  // Bone 0 turns in a plane to 0, 0.5 and 1 rad with radius 2, then 2.5 (a mean radius of
  // 2.25 against the others); bone 1 never turns; bone 2 has zero length in frame 1.
  Bones bones(4, 3);
  const double angles[4] = {0.0, 0.5, 1.0, 1.0};
  for (size_t t = 0; t < 4; ++t) {
    bones.set(t, 0, std::cos(angles[t]), std::sin(angles[t]), 0.0, t == 3 ? 2.5 : 2.0);
    bones.set(t, 1, 0.0, 0.0, 1.0, 1.0 + static_cast<double>(t));
    bones.set(t, 2, t == 1 ? 0.0 : 1.0, 0.0, 0.0, 1.0);
  }
  const std::vector<double> sums = bones.row_sums(1);
  // Row a: sum_b (r_a + r_b) / 2 |phi_a - phi_b|.
  CHECK(sums[0] == doctest::Approx(2.0 * 0.5 + 2.0 * 1.0 + 2.25 * 1.0).epsilon(1e-14));
  CHECK(sums[1] == doctest::Approx(2.0 * 0.5 + 2.0 * 0.5 + 2.25 * 0.5).epsilon(1e-14));
  CHECK(sums[2] == doctest::Approx(2.0 * 1.0 + 2.0 * 0.5 + 0.0).epsilon(1e-14));
  CHECK(sums[3] == doctest::Approx(2.25 * 1.0 + 2.25 * 0.5 + 0.0).epsilon(1e-14));
  for (size_t t = 0; t < 4; ++t) CHECK(sums[4 + t] == 0.0);  // one direction throughout: exactly 0
  // A zero direction makes a right angle with a unit one (|u - v| = |u + v|): pi/2 per pair.
  const double half = 2.0 * std::atan2(1.0, 1.0);
  CHECK(sums[8 + 1] == doctest::Approx(3.0 * half).epsilon(1e-14));
  CHECK(sums[8 + 0] == doctest::Approx(half).epsilon(1e-14));
}

TEST_CASE("posture error is accurate for tiny and opposite turns") {
  Bones bones(2, 2);
  bones.set(0, 0, 1.0, 0.0, 0.0, 1.0);
  bones.set(1, 0, std::cos(1e-9), std::sin(1e-9), 0.0, 1.0);  // arccos of the dot product gives 0
  bones.set(0, 1, 0.0, 1.0, 0.0, 1.0);
  bones.set(1, 1, 0.0, -1.0, 0.0, 1.0);
  const std::vector<double> sums = bones.row_sums(1);
  CHECK(sums[0] == doctest::Approx(1e-9).epsilon(1e-9));
  CHECK(sums[1] == doctest::Approx(1e-9).epsilon(1e-9));
  CHECK(sums[2] == doctest::Approx(4.0 * std::atan(1.0)).epsilon(1e-15));
}

TEST_CASE("posture error does not depend on the thread count") {
  Bones bones(50, 7);
  for (size_t t = 0; t < 50; ++t)
    for (size_t b = 0; b < 7; ++b) {
      const double a = 0.1 * static_cast<double>(t * (b + 1)), c = std::cos(0.3 * static_cast<double>(b));
      bones.set(t, b, std::cos(a) * c, std::sin(a) * c, std::sin(0.3 * static_cast<double>(b)), 1.0 + 0.01 * t);
    }
  CHECK(bones.row_sums(1) == bones.row_sums(3));
  CHECK(bones.row_sums(1) == bones.row_sums(0));
}

TEST_CASE("posture error refuses a non-finite direction, naming the frame and the bone") {
  Bones bones(3, 2);
  bones.set(2, 1, NAN, 0.0, 0.0, 1.0);
  std::vector<double> out(6);
  const animlod::Status status =
      animlod::posture_error_row_sums(bones.directions.data(), bones.radii.data(), 3, 2, 1, out.data());
  CHECK_FALSE(status.ok);
  CHECK(status.message.find("frame 2, bone 1") != std::string::npos);
}
