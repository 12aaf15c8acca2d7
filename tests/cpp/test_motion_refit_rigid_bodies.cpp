// Rigid bodies of the motion re-fit (cpp/src/motion_refit_rigid_bodies.hpp): a kept joint's
// children held by a minimal rigid set become one rotation slot; their lengths hold at any
// value of it, E's gradient through a chain of bodies (and a tree and a leaf hanging from their
// members) matches finite differences away from the start orientation, and the solve without
// the members' variables ends where the solve with every point a variable does.
#include <doctest/doctest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "../../cpp/src/motion_refit_detail.hpp"
#include "../../cpp/src/motion_refit_reduction.hpp"
#include "../../cpp/src/motion_refit_rigid_bodies.hpp"
#include "animlod/motion_refit.hpp"
#include "motion_refit_figure.hpp"

using animlod::detail::PointReduction;
using animlod::detail::RigidBodies;

namespace {

// Root 0 with children 1, 2 (a triangle: body A); 1 with children 3, 4 (body B, its base a
// member of A); a chain 5-6 hanging from 3 (a pendant tree); a leaf 7 on 4; point 8 tied to 2
// and 4, so it stays a variable and its lengths stay equalities.
struct BodyChain : LengthFigure {
  BodyChain()
      : LengthFigure({0, 0, 0,  -0.4, 1, 0,  0.5, 0.9, 0.2,  -0.8, 2, 0.1,  0, 2.1, -0.3,  -1.0, 3, 0.2,
                      -1.1, 4, 0,  0.3, 3, -0.5,  0.6, 2.0, 0.4},
                     {1, 0, 2, 0, 2, 1, 3, 1, 4, 1, 4, 3, 5, 3, 6, 5, 7, 4, 8, 2, 8, 4}, 4.0) {}
};

}  // namespace

TEST_CASE("rigid bodies: minimal rigid sets are found, other groups are not") {
  const BodyChain f;
  const RigidBodies bodies(f.problem, std::vector<uint8_t>(9, 0), true);
  REQUIRE(bodies.count() == 2);
  CHECK(bodies.base(0) == 0);
  CHECK(bodies.members(0) == std::vector<int32_t>{1, 2});
  CHECK(bodies.base(1) == 1);
  CHECK(bodies.members(1) == std::vector<int32_t>{3, 4});
  CHECK(bodies.order() == std::vector<int32_t>{0, 1});
  // The two triangles' six lengths are held by the bodies; 8's two lengths and the chain's are not.
  const std::vector<uint8_t> inner = {1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0};
  CHECK(bodies.inner_equalities() == inner);
  CHECK(RigidBodies(f.problem, std::vector<uint8_t>(9, 0), false).count() == 0);
  std::vector<uint8_t> excluded(9, 0);
  excluded[3] = 1;  // B cannot take 3: a lone child (4) is no body
  CHECK(RigidBodies(f.problem, excluded, true).count() == 1);

  // The figure of the solver tests: 2's children 6, 7, 8 (six lengths and a handed group) form
  // a body; its base 2 hangs from 1 by one length (no body there).
  const Figure figure;
  const RigidBodies handed(figure.problem, std::vector<uint8_t>(9, 0), true);
  REQUIRE(handed.count() == 1);
  CHECK(handed.base(0) == 2);
  CHECK(handed.inner_handed() == std::vector<uint8_t>{1});
}

namespace {

// 1's children: the next joint 2 and a twist joint 3 at `twist` (on the bone between them in
// Unreal's rigs), tied by a length; 4 a leaf on 2.
struct TwistFigure : LengthFigure {
  explicit TwistFigure(std::vector<double> twist)
      : LengthFigure(positions(std::move(twist)), {1, 0, 2, 1, 3, 1, 3, 2, 4, 2}, 3.0) {}
  static std::vector<double> positions(std::vector<double> twist) {
    std::vector<double> key = {0, 0, 0, 0, 1, 0, 0, 3, 0};
    key.insert(key.end(), twist.begin(), twist.end());
    key.insert(key.end(), {0.3, 3.5, 0});
    return key;
  }
};

}  // namespace

TEST_CASE("rigid bodies: a body along a line through its base turns about the axes across it") {
  // As a body of three variables it turned about its line for free, and SLSQP crawled along that
  // direction: 66-108 evaluations per frame on a rig with twist joints.
  const std::vector<std::pair<std::vector<double>, int>> cases = {
      {{0, 2, 0}, 2},     // on the bone
      {{0.04, 2, 0}, 2},  // 2.3 degrees off it
      {{0, 0.5, 0}, 2},   // on the line, on the other side of 1
      {{0.5, 2, 0}, 3},   // 27 degrees off
  };
  for (const auto& [twist, width] : cases) {
    const TwistFigure f(twist);
    const RigidBodies bodies(f.problem, std::vector<uint8_t>(5, 0), true);
    REQUIRE(bodies.count() == 1);
    CHECK(bodies.width(0) == width);
  }
  // Its lengths hold at any value of its two variables, and E's gradient through them is exact.
  const TwistFigure f({0, 2, 0});
  PointReduction reduction(f.problem, true, true, true, false);
  REQUIRE(reduction.variable_count() == 5);  // 1, then the body; 4 a leaf
  const std::vector<double> original = f.perturbed(2, 0.3);
  reduction.set_start(f.key.data(), original.data());
  std::vector<double> y(5);
  reduction.gather(f.key.data(), y.data());
  y[0] += 0.1, y[3] = 0.4, y[4] = -0.7;  // 1 moved, the body turned by about 0.8 rad
  std::vector<double> placed(f.key);
  reduction.fill(y.data(), original.data(), placed.data());
  const std::vector<double> lengths = pair_lengths(placed, f.pairs);
  for (size_t k = 1; k < lengths.size(); ++k)  // 1's own length (k = 0) is SLSQP's to hold
    CHECK(lengths[k] == doctest::Approx(f.key_lengths[k]).epsilon(1e-12));
  check_reduced_gradient(reduction, f.problem, y, original, 0, 1e-6, 1e-6);

  // The solve ends no higher than over every point, where the lengths hold the line only to
  // second order and SLSQP stops higher.
  const size_t frames = 4;
  std::vector<double> originals, fallback;
  for (size_t t = 0; t < frames; ++t) {
    const std::vector<double> o = f.perturbed(20 + static_cast<unsigned>(t), 0.2);
    originals.insert(originals.end(), o.begin(), o.end());
    fallback.insert(fallback.end(), f.key.begin(), f.key.end());
  }
  animlod::MotionRefitOptions options;
  options.ftol_rel = 1e-12;
  options.threads = 1;
  animlod::MotionRefitResult reduced, full;
  REQUIRE(animlod::motion_refit_solve(f.problem, originals.data(), fallback.data(), nullptr, frames, options, reduced));
  options.eliminate_points = false;
  REQUIRE(animlod::motion_refit_solve(f.problem, originals.data(), fallback.data(), nullptr, frames, options, full));
  CHECK(reduced.failures.empty());
  for (size_t t = 0; t < frames; ++t) CHECK(reduced.values[t] <= full.values[t] * (1.0 + 1e-6));
  check_lengths_held(reduced.positions, f.problem.point_count, f.pairs, f.key_lengths, 1e-8 * 3.0);
}

TEST_CASE("rigid bodies: lengths hold at any rotation and E's gradient through the chain is exact") {
  const BodyChain f;
  PointReduction reduction(f.problem, true, true, true, false);
  // Variables: 8, then A's and B's rotation vectors (5, 6 a tree, 7 a leaf, 1-4 members).
  REQUIRE(reduction.variable_count() == 9);
  CHECK(reduction.kept_equality_count() == 2);  // 8-2 and 8-4
  const std::vector<double> original = f.perturbed(1, 0.3);
  const std::vector<double> start = f.key;
  reduction.set_start(start.data(), original.data());
  std::vector<double> y(9);
  reduction.gather(start.data(), y.data());
  CHECK(y[3] == 0.0);
  y[3] = 0.4, y[4] = -0.7, y[5] = 0.2;  // A turned by about 0.83 rad
  y[6] = -0.1, y[7] = 0.3, y[8] = 0.5;
  y[0] += 0.2;                          // 8 moved
  std::vector<double> placed(start);
  reduction.fill(y.data(), original.data(), placed.data());
  const std::vector<double> lengths = pair_lengths(placed, f.pairs);
  for (size_t k = 0; k < 9; ++k) CHECK(lengths[k] == doctest::Approx(f.key_lengths[k]).epsilon(1e-12));

  check_reduced_gradient(reduction, f.problem, y, original, 0, 1e-6, 1e-6);
  // Near the start orientation (the series branch of the rotation) as well.
  std::fill(y.begin() + 3, y.end(), 1e-6);
  check_reduced_gradient(reduction, f.problem, y, original, 3, 1e-7, 1e-5);
}

TEST_CASE("rigid bodies: the solve over rotations ends where the solve over every point does") {
  const BodyChain f;
  const auto run = solve_with_and_without_elimination(f.problem, f.key, 40, 0.2, 8);
  check_lengths_held(run.without.positions, f.problem.point_count, f.pairs, f.key_lengths, 1e-8 * 4.0);
}
