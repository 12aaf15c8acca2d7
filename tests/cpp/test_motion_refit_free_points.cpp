// Free points of the motion re-fit (cpp/src/motion_refit_free_points.hpp): minimised for given
// positions of the others, they leave E's gradient over the others unchanged (the envelope
// theorem) and the reduced Hessian is the Schur complement; the solve without their variables
// ends where the solve with them does, a problem of free points only needs no SLSQP, and a
// cluster's remembered minimum is reused only for the same frame and held points.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "../../cpp/src/motion_refit_detail.hpp"
#include "../../cpp/src/motion_refit_free_points.hpp"
#include "../../cpp/src/motion_refit_reduction.hpp"
#include "animlod/motion_refit.hpp"
#include "motion_refit_figure.hpp"

using animlod::MotionRefitOptions;
using animlod::MotionRefitResult;
using animlod::detail::FreePointClusters;
using animlod::detail::PointReduction;

TEST_CASE("free points: the reduced gradient and Hessian are those of E minimised over them") {
  const Figure f;  // points 3 and 4 (a frozen joint and its child) are in no length
  const size_t p = f.problem.point_count;
  const std::vector<double> original = f.perturbed(1, 0.05);
  const std::vector<double> x = f.perturbed(2, 0.1);
  // Without hard constraints nothing is substituted: points 1, 2, 5, 6, 7, 8 stay variables.
  PointReduction reduction(f.problem, false, true, true);
  REQUIRE(reduction.reduced_points() == 6);
  reduction.set_start(x.data(), original.data());
  std::vector<double> y(3 * reduction.reduced_points());
  reduction.gather(x.data(), y.data());
  const size_t n = y.size();

  std::vector<double> gradient(n);
  reduced_energy(reduction, f.problem, y, original, gradient);
  std::vector<double> placed(x), full(3 * p);  // the free points sit where their gradient vanishes
  reduction.fill(y.data(), original.data(), placed.data());
  animlod::detail::refit_objective_frame(f.problem, placed.data(), original.data(), full.data());
  double scale = 0.0;
  for (double g : full) scale = std::max(scale, std::abs(g));
  for (size_t i = 9; i < 15; ++i) CHECK(std::abs(full[i]) < 1e-8 * scale);

  const double h = 1e-6;
  std::vector<double> g_plus(n), g_minus(n), numeric_hessian(n * n);
  for (size_t i = 0; i < n; ++i) {
    const double numeric = reduced_energy_slope(reduction, f.problem, y, original, i, h, g_plus, g_minus);
    CHECK(gradient[i] == doctest::Approx(numeric).epsilon(1e-6).scale(1.0));
    for (size_t j = 0; j < n; ++j) numeric_hessian[j * n + i] = (g_plus[j] - g_minus[j]) / (2 * h);
  }
  const size_t m = 3 * (p - 1);
  std::vector<double> hessian(m * m), reduced(n * n);
  animlod::detail::refit_hessian_frame(f.problem, placed.data(), false, hessian.data());
  reduction.reduce_matrix(hessian.data(), reduced.data());
  for (size_t k = 0; k < n * n; ++k) CHECK(reduced[k] == doctest::Approx(numeric_hessian[k]).epsilon(1e-5).scale(1.0));
}

TEST_CASE("free points: the solve without their variables ends where the solve with them does") {
  const Figure f;
  const size_t p = f.problem.point_count;
  const size_t frames = 6;
  const auto [with, without] = solve_with_and_without_elimination(f.problem, f.key, 10, 0.05, frames);
  for (size_t t = 0; t < frames; ++t) {
    for (size_t i = 0; i < 3 * p; ++i)
      CHECK(without.positions[t * 3 * p + i] == doctest::Approx(with.positions[t * 3 * p + i]).epsilon(1e-4).scale(1.0));
  }
}

TEST_CASE("free points: a problem of free points only is solved without SLSQP") {
  // Root 0, a frozen joint 1 and its child 2: no length, one angle.
  const std::vector<int32_t> triple = {0, 1, 2};
  const std::vector<double> key_cosine = {-0.5};
  animlod::MotionRefitProblem problem;
  problem.point_count = 3;
  problem.angle_triples = triple.data();
  problem.key_cosines = key_cosine.data();
  problem.angle_triple_count = 1;
  const std::vector<double> original = {0, 0, 0, 0, 1, 0, 0.1, 2, 0};  // nearly straight
  MotionRefitResult out;
  REQUIRE(animlod::motion_refit_solve(problem, original.data(), original.data(), nullptr, 1, MotionRefitOptions{}, out));
  CHECK(out.failures.empty());
  CHECK(out.evaluations[0] == 1);
  CHECK(out.values[0] < animlod::detail::refit_objective_frame(problem, original.data(), original.data(), nullptr));
  std::vector<double> gradient(9);
  animlod::detail::refit_objective_frame(problem, out.positions.data(), original.data(), gradient.data());
  for (double g : gradient) CHECK(std::abs(g) < 1e-10);
}

TEST_CASE("free points: a remembered minimum answers only the same frame and held points") {
  const Figure f;  // triple (2, 3, 4): 3 and 4 free, 2 held
  const size_t p = f.problem.point_count;
  std::vector<uint8_t> free(p, 0);
  free[3] = free[4] = 1;
  const std::vector<double> original_a = f.perturbed(1, 0.05), original_b = f.perturbed(3, 0.05);
  const std::vector<double> x = f.perturbed(2, 0.1);
  // Each case against clusters that never minimised before.
  auto fresh = [&](const std::vector<double>& at, const std::vector<double>& original) {
    FreePointClusters clusters(f.problem, free);
    clusters.set_start(x.data(), original.data());
    std::vector<double> out(at);
    clusters.minimise(out.data(), original.data());
    return out;
  };
  FreePointClusters clusters(f.problem, free);
  clusters.set_start(x.data(), original_a.data());
  std::vector<double> first(x), again(x);
  clusters.minimise(first.data(), original_a.data());
  clusters.minimise(again.data(), original_a.data());
  CHECK(again == first);
  std::vector<double> moved(x);  // the held point moves
  moved[3 * 2] += 0.05;
  clusters.minimise(moved.data(), original_a.data());
  CHECK(moved == fresh(moved, original_a));
  CHECK(moved[3 * 3] != first[3 * 3]);
  clusters.set_start(x.data(), original_b.data());  // the next frame, the held point as last time
  std::vector<double> next(moved);
  clusters.minimise(next.data(), original_b.data());
  CHECK(next == fresh(moved, original_b));
  CHECK(next[3 * 3] != moved[3 * 3]);
}
