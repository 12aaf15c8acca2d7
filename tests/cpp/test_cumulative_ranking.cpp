#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "animlod/cumulative_ranking.hpp"

namespace {

// A figure in the xy plane: the root at the origin, two arms of two joints each along +x (joints 1,
// 2) and -x (joints 3, 4), one unit per bone; every joint turns about z by its own angle per frame.
struct ArmsFigure {
  static constexpr size_t kJoints = 5;
  const int32_t parents[kJoints] = {-1, 0, 1, 0, 3};
  const double offsets[kJoints] = {0.0, 1.0, 1.0, -1.0, -1.0};  // x of each joint in its parent
  size_t frames;
  std::vector<double> angles;  // (n, J)

  explicit ArmsFigure(size_t n) : frames(n), angles(n * kJoints, 0.0) {}

  void local(size_t frame, size_t joint, double* m) const {
    const double a = angles[frame * kJoints + joint], c = std::cos(a), s = std::sin(a);
    const double values[16] = {c, -s, 0, offsets[joint], s, c, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    std::copy(values, values + 16, m);
  }
  std::vector<double> world() const {  // (n, J, 4, 4) by forward kinematics
    std::vector<double> out(16 * frames * kJoints);
    for (size_t f = 0; f < frames; ++f)
      for (size_t j = 0; j < kJoints; ++j) {
        double* m = &out[16 * (f * kJoints + j)];
        local(f, j, m);
        if (parents[j] < 0) continue;
        const double* p = &out[16 * (f * kJoints + static_cast<size_t>(parents[j]))];
        double product[16];
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c) {
            product[4 * r + c] = 0.0;
            for (int k = 0; k < 4; ++k) product[4 * r + c] += p[4 * r + k] * m[4 * k + c];
          }
        std::copy(product, product + 16, m);
      }
    return out;
  }
  std::vector<double> key_local() const {  // frame 0 is every joint's key frame
    std::vector<double> out(16 * kJoints);
    for (size_t j = 0; j < kJoints; ++j) local(0, j, &out[16 * j]);
    return out;
  }
  std::vector<double> steps(const uint8_t* candidates) const {
    std::vector<double> scores(kJoints, -1.0);
    const std::vector<double> w = world(), key = key_local();
    const animlod::Status status =
        animlod::cumulative_freeze_steps(w.data(), key.data(), parents, candidates, frames, kJoints, scores.data());
    REQUIRE_MESSAGE(status.ok, status.message);
    return scores;
  }
};

}  // namespace

TEST_CASE("cumulative ranking: still joints first, then the arm whose freeze moves the figure least") {
  ArmsFigure figure(12);
  for (size_t f = 0; f < figure.frames; ++f) {
    const double t = static_cast<double>(f);
    figure.angles[f * 5 + 1] = 0.9 * std::sin(0.5 * t);   // the +x shoulder swings widely
    figure.angles[f * 5 + 2] = 0.3;                         // elbows held at their key angle
    figure.angles[f * 5 + 3] = 0.1 * std::sin(0.5 * t);   // the -x shoulder barely moves
    figure.angles[f * 5 + 4] = -0.7;
  }
  const uint8_t candidates[5] = {0, 1, 1, 1, 1};
  const std::vector<double> steps = figure.steps(candidates);
  CHECK(steps[0] == std::numeric_limits<double>::infinity());
  // The elbows cost nothing (a rounding-level cost counts as 0): they go by index.
  CHECK(steps[2] == 0.0);
  CHECK(steps[4] == 1.0);
  CHECK(steps[3] == 2.0);
  CHECK(steps[1] == 3.0);
}

TEST_CASE("cumulative ranking: mirror joints tie whatever the rounding, and go by index") {
  ArmsFigure figure(17);
  for (size_t f = 0; f < figure.frames; ++f) {
    const double t = 0.37 * static_cast<double>(f) + 0.1;
    figure.angles[f * 5 + 0] = 0.3 + 0.2 * std::sin(t);  // the figure turns: the arms' sums round apart
    figure.angles[f * 5 + 1] = 0.6 * std::sin(t);  // the two arms mirror each other
    figure.angles[f * 5 + 3] = -0.6 * std::sin(t);
    figure.angles[f * 5 + 2] = 0.4 * std::cos(t);
    figure.angles[f * 5 + 4] = -0.4 * std::cos(t);
  }
  const uint8_t candidates[5] = {0, 1, 1, 1, 1};
  const std::vector<double> steps = figure.steps(candidates);
  // Each elbow costs less than its shoulder; a mirror pair ties: the lower index first.
  CHECK(steps[2] == 0.0);
  CHECK(steps[4] == 1.0);
  CHECK(steps[1] == 2.0);
  CHECK(steps[3] == 3.0);
  const uint8_t one_arm[5] = {0, 0, 0, 1, 1};  // non-candidates never freeze
  const std::vector<double> some = figure.steps(one_arm);
  CHECK(some[1] == std::numeric_limits<double>::infinity());
  CHECK(some[4] == 0.0);
  CHECK(some[3] == 1.0);
}

TEST_CASE("cumulative ranking names bad input") {
  ArmsFigure figure(3);
  std::vector<double> world = figure.world();
  const std::vector<double> key = figure.key_local();
  std::vector<double> scores(5);
  const uint8_t candidates[5] = {0, 1, 1, 1, 1};
  const int32_t late_parent[5] = {-1, 2, 0, 0, 3};
  animlod::Status status =
      animlod::cumulative_freeze_steps(world.data(), key.data(), late_parent, candidates, 3, 5, scores.data());
  CHECK(status.message == "skeleton: joint 1 has parent 2, expected -1 or a joint before it (topological order)");
  const uint8_t root_candidate[5] = {1, 1, 1, 1, 1};
  status = animlod::cumulative_freeze_steps(world.data(), key.data(), figure.parents, root_candidate, 3, 5,
                                            scores.data());
  CHECK(status.message == "candidates[0]: the root cannot freeze");
  world[16 * (2 * 5 + 4) + 3] = std::nan("");
  status = animlod::cumulative_freeze_steps(world.data(), key.data(), figure.parents, candidates, 3, 5, scores.data());
  CHECK(status.message == "world[2, 4]: not a finite transform");
}
