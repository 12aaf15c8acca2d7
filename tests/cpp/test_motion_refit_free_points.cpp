// Free points of the motion re-fit (cpp/src/motion_refit_free_points.hpp): minimised for given
// positions of the others, they leave E's gradient over the others unchanged (the envelope
// theorem) and the reduced Hessian is the Schur complement; the solve without their variables
// ends where the solve with them does, a problem of free points only needs no SLSQP, the fixed
// start moves with the held points, a cluster follows the valley it is in as its held points
// turn, and held points met before in a frame get the minimum they got then.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <utility>
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
  PointReduction reduction(f.problem, false, true, true, false);
  REQUIRE(reduction.variable_count() == 18);
  reduction.set_start(x.data(), original.data());
  std::vector<double> y(reduction.variable_count());
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

// Points tied by angle terms only (no length): the problems of the chain tests below.
struct AngleChain {
  const std::vector<int32_t> triples;
  const std::vector<double> key_cosines, original;
  const std::vector<uint8_t> free;
  animlod::MotionRefitProblem problem;
  AngleChain(std::vector<int32_t> t, std::vector<double> cosines, std::vector<double> x, std::vector<uint8_t> f)
      : triples(std::move(t)), key_cosines(std::move(cosines)), original(std::move(x)), free(std::move(f)) {
    problem.point_count = free.size();
    problem.angle_triples = triples.data();
    problem.key_cosines = key_cosines.data();
    problem.angle_triple_count = key_cosines.size();
  }
  AngleChain(const AngleChain&) = delete;  // problem points into this chain's vectors
  double energy(const std::vector<double>& x) const {
    return animlod::detail::refit_objective_frame(problem, x.data(), original.data(), nullptr);
  }
};

// A chain 0-1-2-3, its root held and moved in steps, 1 and 2 frozen (two angle terms, several
// minima). From the fixed start where it was (its minimum for the root at the origin), Newton
// fell into a higher minimum than the valley the steps follow; moved with the root, it lands in
// that valley.
struct BentChain : AngleChain {
  BentChain()
      : AngleChain({0, 1, 2, 1, 2, 3}, {0.2707, -0.1345},
                   {0, 0, 0, -0.0713, 0.7933, 0.1751, 0.2238, 1.7442, 0.1733, -0.2592, 2.9772, -0.1064}, {0, 1, 1, 1}) {}
  // The root at step s of 8 towards (-0.406, 0.0771, 0.0712).
  std::vector<double> moved(std::vector<double> x, int step) const {
    const double move[3] = {-0.406, 0.0771, 0.0712};
    for (int a = 0; a < 3; ++a) x[a] = move[a] * step / 8;
    return x;
  }
};

// A chain 0-1-2-3-4 whose held points 0 and 1 turn about 0 in steps; 2, 3 and 4 are frozen.
// Moving the fixed start with the held points' mean does not turn it: only the latest minimum
// follows the valley.
struct TurningChain : AngleChain {
  TurningChain()
      : AngleChain({0, 1, 2, 1, 2, 3, 2, 3, 4}, {0.9434564, 0.7987762, 0.8132009},  // of the original
                   {0, 0, 0, 0, 1, 0, 0.3, 1.9, 0.1, 0.1, 2.9, -0.2, -0.3, 3.8, 0.1}, {0, 0, 1, 1, 1}) {}
  // Point 1 at step s of 8 of a 0.6 rad turn about z.
  std::vector<double> moved(std::vector<double> x, int step) const {
    const double angle = 0.6 * step / 8;
    x[3] = -std::sin(angle), x[4] = std::cos(angle), x[5] = 0.0;
    return x;
  }
};

// E after the chain's held points moved in 8 steps, minimised at each, and E of the last step
// minimised as the first of a frame (from the fixed start only).
template <typename Chain>
std::pair<double, double> stepped_and_fixed_start_only(const Chain& chain) {
  FreePointClusters clusters(chain.problem, chain.free), fresh(chain.problem, chain.free);
  clusters.set_start(chain.original.data(), chain.original.data());
  fresh.set_start(chain.original.data(), chain.original.data());
  std::vector<double> x(chain.original);
  for (int step = 1; step <= 8; ++step) {
    x = chain.moved(x, step);
    clusters.minimise(x.data(), chain.original.data());
  }
  std::vector<double> alone = chain.moved(chain.original, 8);
  fresh.minimise(alone.data(), chain.original.data());
  return {chain.energy(x), chain.energy(alone)};
}

TEST_CASE("free points: the fixed start moves with its held points") {
  const auto [stepped, fixed_start_only] = stepped_and_fixed_start_only(BentChain());
  // Where it stayed, its minimum was 0.5% above the valley's or more.
  CHECK(fixed_start_only < 1.001 * stepped);
}

TEST_CASE("free points: the latest minimum keeps a turning cluster in its valley") {
  const auto [stepped, fixed_start_only] = stepped_and_fixed_start_only(TurningChain());
  CHECK(stepped < 0.98 * fixed_start_only);  // 4% lower
}

TEST_CASE("free points: held points met before in a frame get the minimum they got then") {
  const BentChain chain;
  FreePointClusters clusters(chain.problem, chain.free);
  clusters.set_start(chain.original.data(), chain.original.data());
  std::vector<double> x(chain.original), at_four;
  for (int step = 1; step <= 8; ++step) {
    x = chain.moved(x, step);
    clusters.minimise(x.data(), chain.original.data());
    if (step == 4) at_four = x;
  }
  std::vector<double> again = chain.moved(x, 4);
  clusters.minimise(again.data(), chain.original.data());
  CHECK(again == at_four);
  // The next frame forgets them: from the same start, the last root position is minimised as
  // if first met.
  FreePointClusters fresh(chain.problem, chain.free);
  fresh.set_start(chain.original.data(), chain.original.data());
  std::vector<double> first = chain.moved(chain.original, 8);
  fresh.minimise(first.data(), chain.original.data());
  clusters.set_start(chain.original.data(), chain.original.data());
  std::vector<double> next = chain.moved(x, 8);
  clusters.minimise(next.data(), chain.original.data());
  CHECK(next == first);
  CHECK(next != x);
}
