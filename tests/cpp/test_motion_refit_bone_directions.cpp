// Bone directions of the motion re-fit (cpp/src/motion_refit_bone_directions.hpp): the held
// lengths among the points that stay in the solve become a spanning forest of directions (two
// variables each, the lengths outside it equalities); the lengths hold at any direction, E's
// gradient through the chain matches finite differences, gather inverts fill, and the solve over
// directions ends where the solve over every point does.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "../../cpp/src/motion_refit_reduction.hpp"
#include "animlod/motion_refit.hpp"
#include "motion_refit_figure.hpp"

using animlod::detail::PointReduction;

namespace {

// Root 0; a chain 1-2-3 from it, 3 also held by a length to the root (a loop: one of its lengths
// stays an equality); a leaf 4 on 3; a frozen joint 5 below 3 with its end site 6 (free points
// whose angle term reaches 3, so the chain is no pendant tree).
struct LoopedChain : LengthFigure {
  std::vector<int32_t> triples = {3, 5, 6};
  std::vector<double> key_cosines = {0.0};

  LoopedChain()
      : LengthFigure({0, 0, 0,  0, 1, 0,  0.2, 2, 0,  0.1, 3, 0.2,  0.3, 4, 0,  1, 3.2, 0,  2, 3.3, 0.1},
                     {1, 0, 2, 1, 3, 2, 4, 3, 3, 0}, 4.0) {
    std::vector<double> u(3), v(3);
    for (int a = 0; a < 3; ++a) u[a] = key[3 * 3 + a] - key[3 * 5 + a], v[a] = key[3 * 6 + a] - key[3 * 5 + a];
    key_cosines[0] = (u[0] * v[0] + u[1] * v[1] + u[2] * v[2]) /
                     std::sqrt((u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
    problem.angle_triples = triples.data();
    problem.key_cosines = key_cosines.data();
    problem.angle_triple_count = 1;
  }
};

}  // namespace

TEST_CASE("bone directions: a forest of the held lengths whose lengths hold at any direction") {
  const LoopedChain f;
  PointReduction reduction(f.problem, true, true, true, true);
  // 1 and 3 hang from the root, 2 from 1: three directions; 3-2 stays an equality.
  CHECK(reduction.variable_count() == 6);
  CHECK(reduction.kept_equality_count() == 1);
  CHECK(PointReduction(f.problem, true, true, true, false).variable_count() == 9);
  CHECK(PointReduction(f.problem, false, true, true, true).variable_count() == 9);  // soft lengths

  const std::vector<double> original = f.perturbed(1, 0.3);
  reduction.set_start(f.key.data(), original.data());
  std::vector<double> y(6);
  reduction.gather(f.key.data(), y.data());
  for (double v : y) CHECK(v == doctest::Approx(0.0).scale(1.0).epsilon(1e-15));
  y = {0.4, -0.7, 1.1, 0.3, -0.2, 0.9};
  std::vector<double> placed(f.key);
  reduction.fill(y.data(), original.data(), placed.data());
  const std::vector<double> lengths = pair_lengths(placed, f.pairs);
  for (size_t k : {0, 1, 3, 4}) CHECK(lengths[k] == doctest::Approx(f.key_lengths[k]).epsilon(1e-12));
  std::vector<double> back(6);
  reduction.gather(placed.data(), back.data());
  for (size_t i = 0; i < 6; ++i) CHECK(back[i] == doctest::Approx(y[i]).epsilon(1e-12));

  // (A step of 1e-4: at 1e-6 and 1e-5 the frozen joint's Newton ends its two starts on either
  // side of a rounding tie along one direction, which moves the difference quotient by 3e-5.)
  check_reduced_gradient(reduction, f.problem, y, original, 0, 1e-4, 1e-6);
  // Near the start direction (the series branch of the chart) as well.
  std::fill(y.begin(), y.end(), 2e-5);
  check_reduced_gradient(reduction, f.problem, y, original, 0, 1e-6, 1e-6);
}

TEST_CASE("bone directions: the solve over directions ends where the solve over every point does") {
  const LoopedChain f;
  const auto run = solve_with_and_without_elimination(f.problem, f.key, 60, 0.2, 8);
  check_lengths_held(run.without.positions, f.problem.point_count, f.pairs, f.key_lengths, 1e-8 * 4.0);
}
