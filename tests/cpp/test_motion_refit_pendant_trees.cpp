// Pendant trees of the motion re-fit (cpp/src/motion_refit_pendant_trees.hpp): a chain hanging
// by held lengths alone is solved inside; E's gradient over the others through it matches finite
// differences of E at the placed tree, and the solve without its variables ends where the solve
// with them does, its lengths held.
#include <doctest/doctest.h>

#include <cmath>
#include <vector>

#include "../../cpp/src/motion_refit_detail.hpp"
#include "../../cpp/src/motion_refit_reduction.hpp"
#include "animlod/motion_refit.hpp"
#include "motion_refit_figure.hpp"

using animlod::detail::PointReduction;

namespace {

// Root 0; points 1, 2, 3 in a loop of lengths with the root (0-1, 0-2, 1-3, 2-3), so none of them
// hangs; the chain 4-5-6 hangs from 3, and 7 is a leaf on 1 (a one-point tree: closed form).
struct ChainFigure : LengthFigure {
  ChainFigure()
      : LengthFigure({0, 0, 0,  -0.5, 1, 0,  0.5, 1, 0.1,  0, 2, 0,  0.2, 3, 0,  0.1, 4, 0.3,  0.4, 5, 0.2,
                      -1.2, 1.3, 0},
                     {0, 1, 0, 2, 1, 3, 2, 3, 3, 4, 4, 5, 5, 6, 1, 7}, 5.0) {}
};

}  // namespace

TEST_CASE("pendant trees: the chain leaves the variables and E's gradient through it is exact") {
  const ChainFigure f;
  PointReduction reduction(f.problem, true, true, true, false);
  CHECK(reduction.variable_count() == 9);        // 1, 2 and 3
  CHECK(reduction.kept_equality_count() == 4);  // the loop's lengths
  const std::vector<double> original = f.perturbed(1, 0.3);
  const std::vector<double> x = f.perturbed(2, 0.1);
  std::vector<double> y(9);
  reduction.gather(x.data(), y.data());
  std::vector<double> placed(x);
  reduction.fill(y.data(), original.data(), placed.data());
  const std::vector<double> lengths = pair_lengths(placed, f.pairs);
  for (size_t k = 4; k < 7; ++k) CHECK(lengths[k] == doctest::Approx(f.key_lengths[k]).epsilon(1e-12));

  check_reduced_gradient(reduction, f.problem, y, original, 0, 1e-6, 1e-6);
}

TEST_CASE("pendant trees: the solve without their variables ends where the solve with them does") {
  const ChainFigure f;
  const auto run = solve_with_and_without_elimination(f.problem, f.key, 20, 0.2, 8);
  check_lengths_held(run.without.positions, f.problem.point_count, f.pairs, f.key_lengths, 1e-8 * 5.0);
}
