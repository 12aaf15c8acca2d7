// Motion LoD re-fit in the core: E's gradient, the Hessian used as preconditioner and the
// constraint Jacobians against finite differences; the solve keeps bones, ends feasible from an
// infeasible start (also one off by rounding only, whose E must rise), does not depend on the
// thread count, and rejects bad input by name.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "../../cpp/src/motion_refit_detail.hpp"
#include "animlod/motion_refit.hpp"
#include "motion_refit_figure.hpp"

using animlod::MotionRefitOptions;
using animlod::MotionRefitProblem;
using animlod::MotionRefitResult;

namespace {
// equality_rows describes refit_equalities_frame's rows: each row's Jacobian (rows of (P, 3) at
// x) is zero outside the points equality_rows gives it.
void check_rows_read_their_points(const MotionRefitProblem& problem, const std::vector<double>& jacobian) {
  const std::vector<animlod::detail::EqualityRow> rows = animlod::detail::equality_rows(problem);
  REQUIRE(rows.size() == animlod::motion_refit_equality_count(problem));
  const size_t p = problem.point_count;
  for (size_t r = 0; r < rows.size(); ++r)
    for (size_t k = 0; k < p; ++k) {
      const bool read = std::find(rows[r].points.begin(), rows[r].points.begin() + rows[r].width,
                                  static_cast<int32_t>(k)) != rows[r].points.begin() + rows[r].width;
      double largest = 0.0;
      for (int a = 0; a < 3; ++a) largest = std::max(largest, std::abs(jacobian[r * 3 * p + 3 * k + a]));
      if (!read) CHECK(largest == 0.0);
      else if (k != 0) CHECK(largest > 0.0);
    }
}
}  // namespace

TEST_CASE("motion refit: E's gradient and Hessian match finite differences") {
  const Figure f;
  const std::vector<double> original = f.perturbed(1, 0.05);
  const std::vector<double> x = f.perturbed(2, 0.2);
  const size_t p = f.problem.point_count;
  std::vector<double> gradient(3 * p);
  animlod::detail::refit_objective_frame(f.problem, x.data(), original.data(), gradient.data());
  const double h = 1e-6;
  for (size_t i = 3; i < 3 * p; ++i) {
    std::vector<double> plus = x, minus = x;
    plus[i] += h;
    minus[i] -= h;
    const double numeric = (objective_at(f.problem, plus, original) - objective_at(f.problem, minus, original)) / (2 * h);
    CHECK(gradient[i] == doctest::Approx(numeric).epsilon(1e-6).scale(1.0));
  }
  CHECK(gradient[0] == 0.0);

  const size_t n = 3 * (p - 1);
  std::vector<double> hessian(n * n);
  animlod::detail::refit_hessian_frame(f.problem, x.data(), false, hessian.data());
  for (size_t j = 0; j < n; ++j) {
    std::vector<double> plus = x, minus = x, g_plus(3 * p), g_minus(3 * p);
    plus[3 + j] += h;
    minus[3 + j] -= h;
    animlod::detail::refit_objective_frame(f.problem, plus.data(), original.data(), g_plus.data());
    animlod::detail::refit_objective_frame(f.problem, minus.data(), original.data(), g_minus.data());
    for (size_t i = 0; i < n; ++i)
      CHECK(hessian[i * n + j] == doctest::Approx((g_plus[3 + i] - g_minus[3 + i]) / (2 * h)).epsilon(1e-5).scale(1.0));
  }
  // The preconditioner's form is positive definite even where the exact Hessian is not.
  animlod::detail::refit_hessian_frame(f.problem, x.data(), true, hessian.data());
  for (size_t k = 0; k < n; ++k) {  // Cholesky without pivoting succeeds
    for (size_t j = 0; j < k; ++j) hessian[k * n + k] -= hessian[k * n + j] * hessian[k * n + j];
    REQUIRE(hessian[k * n + k] > 0.0);
    hessian[k * n + k] = std::sqrt(hessian[k * n + k]);
    for (size_t i = k + 1; i < n; ++i) {
      for (size_t j = 0; j < k; ++j) hessian[i * n + k] -= hessian[i * n + j] * hessian[k * n + j];
      hessian[i * n + k] /= hessian[k * n + k];
    }
  }
}

TEST_CASE("motion refit: constraint Jacobians match finite differences") {
  const Figure f;
  const std::vector<double> x = f.perturbed(3, 0.2);
  const size_t p = f.problem.point_count;
  const size_t m = animlod::motion_refit_equality_count(f.problem);
  REQUIRE(m == f.key_lengths.size() + 3);
  std::vector<double> values(m), jacobian(m * 3 * p), plus_values(m), minus_values(m);
  REQUIRE(animlod::motion_refit_equalities(f.problem, x.data(), 1, values.data(), jacobian.data()));
  std::vector<double> handed(1), handed_jacobian(3 * p), handed_plus(1), handed_minus(1);
  REQUIRE(animlod::motion_refit_handedness(f.problem, x.data(), 1, handed.data(), handed_jacobian.data()));
  const double h = 1e-6;
  for (size_t i = 3; i < 3 * p; ++i) {
    std::vector<double> plus = x, minus = x;
    plus[i] += h;
    minus[i] -= h;
    animlod::detail::refit_equalities_frame(f.problem, plus.data(), plus_values.data(), nullptr);
    animlod::detail::refit_equalities_frame(f.problem, minus.data(), minus_values.data(), nullptr);
    for (size_t r = 0; r < m; ++r)
      CHECK(jacobian[r * 3 * p + i] == doctest::Approx((plus_values[r] - minus_values[r]) / (2 * h)).scale(1.0));
    animlod::detail::refit_handedness_frame(f.problem, plus.data(), handed_plus.data(), nullptr);
    animlod::detail::refit_handedness_frame(f.problem, minus.data(), handed_minus.data(), nullptr);
    CHECK(handed_jacobian[i] == doctest::Approx((handed_plus[0] - handed_minus[0]) / (2 * h)).scale(1.0));
  }
  for (size_t r = 0; r < m; ++r) CHECK(jacobian[r * 3 * p + 1] == 0.0);  // the root is not a variable
  check_rows_read_their_points(f.problem, jacobian);
  // At the key posture every equality holds and the handed group is on its side.
  REQUIRE(animlod::motion_refit_equalities(f.problem, f.key.data(), 1, values.data(), nullptr));
  for (double v : values) CHECK(std::abs(v) < 1e-12);
  REQUIRE(animlod::motion_refit_handedness(f.problem, f.key.data(), 1, handed.data(), nullptr));
  CHECK(handed[0] < 0.0);
}

TEST_CASE("motion refit: a solve started infeasible ends feasible, whatever the thread count") {
  Figure f;
  const size_t p = f.problem.point_count;
  const size_t frames = 12;
  std::vector<double> original, fallback, cold;
  for (size_t t = 0; t < frames; ++t) {
    const std::vector<double> o = f.perturbed(10 + unsigned(t), 0.08);
    original.insert(original.end(), o.begin(), o.end());
    fallback.insert(fallback.end(), f.key.begin(), f.key.end());
    for (size_t i = 0; i < 3; ++i) fallback[t * 3 * p + i] = o[i];  // the root where it is
  }
  // Cold starts off every constraint: stretched 10 % away from the root.
  cold = fallback;
  for (size_t t = 0; t < frames; ++t)
    for (size_t i = 3; i < 3 * p; ++i) cold[t * 3 * p + i] = 1.1 * cold[t * 3 * p + i];
  std::vector<double> violation(animlod::motion_refit_equality_count(f.problem));
  REQUIRE(animlod::motion_refit_equalities(f.problem, cold.data(), 1, violation.data(), nullptr));
  REQUIRE(*std::max_element(violation.begin(), violation.end()) > 1e-2);

  MotionRefitOptions options;
  options.warm_start = false;  // every frame from its (infeasible) cold start
  options.chunk_frames = 4;
  options.threads = 1;
  MotionRefitResult one;
  REQUIRE(animlod::motion_refit_solve(f.problem, original.data(), fallback.data(), cold.data(), frames, options, one));
  CHECK(one.failures.empty());
  std::vector<double> values(violation.size()), handed(1);
  for (size_t t = 0; t < frames; ++t) {
    animlod::detail::refit_equalities_frame(f.problem, one.positions.data() + t * 3 * p, values.data(), nullptr);
    for (double v : values) CHECK(std::abs(v) <= options.feasibility_tolerance);
    animlod::detail::refit_handedness_frame(f.problem, one.positions.data() + t * 3 * p, handed.data(), nullptr);
    CHECK(handed[0] <= 0.0);
    // The re-fit is better than the feasible fallback.
    const std::vector<double> o(original.begin() + long(t * 3 * p), original.begin() + long((t + 1) * 3 * p));
    const std::vector<double> b(fallback.begin() + long(t * 3 * p), fallback.begin() + long((t + 1) * 3 * p));
    CHECK(one.values[t] < objective_at(f.problem, b, o));
  }

  options.warm_start = true;
  options.threads = 1;
  MotionRefitResult serial, parallel;
  REQUIRE(animlod::motion_refit_solve(f.problem, original.data(), fallback.data(), nullptr, frames, options, serial));
  options.threads = 3;
  REQUIRE(animlod::motion_refit_solve(f.problem, original.data(), fallback.data(), nullptr, frames, options, parallel));
  CHECK(serial.positions == parallel.positions);
  CHECK(serial.evaluations == parallel.evaluations);
}

TEST_CASE("motion refit: a start off its lengths by key rounding is solved, not refused") {
  // A clip whose joint translations are float32 keys moves its held lengths by ~1e-7 L from the
  // key posture's, so its own positions, the start, are feasible only up to that. Holding the
  // lengths can then cost more Ed than the Es it removes (Xbot's hips: a rigid set of 10 lengths
  // over 8 points, 3x), and E rises above the start's: the solve's work, not a failure (which
  // fell back to the frozen key motion). Here Es weighs little, for the same effect.
  LengthFigure f({0, 0, 0, 0, 1, 0, 0, 2, 0, 1, 2, 0, 1, 3, 0}, {1, 0, 2, 1, 3, 2, 4, 3}, 2.0);
  f.problem.string_weight = 0.02;
  const size_t p = f.problem.point_count;
  std::vector<double> start(f.key);
  for (size_t i = 3; i < 3 * p; ++i) start[i] *= 1.0 + 1e-7;  // lengths 1e-7 longer
  const std::vector<double>& original = start;
  std::vector<double> violation(animlod::motion_refit_equality_count(f.problem));
  REQUIRE(animlod::motion_refit_equalities(f.problem, start.data(), 1, violation.data(), nullptr));
  MotionRefitOptions options;
  options.threads = 1;
  options.eliminate_points = false;  // eliminated points would be placed on their lengths at once
  REQUIRE(*std::max_element(violation.begin(), violation.end()) > options.feasibility_tolerance);
  MotionRefitResult out;
  REQUIRE(animlod::motion_refit_solve(f.problem, original.data(), start.data(), start.data(), 1, options, out));
  CHECK(out.failures.empty());
  CHECK(out.values[0] > objective_at(f.problem, start, original));  // E rose: the lengths hold
  animlod::detail::refit_equalities_frame(f.problem, out.positions.data(), violation.data(), nullptr);
  for (double v : violation) CHECK(std::abs(v) <= options.feasibility_tolerance);
}

TEST_CASE("motion refit: bad problems and inputs are refused by name") {
  Figure f;
  std::vector<int32_t> bad_triples = {2, 3, 41};
  MotionRefitProblem problem = f.problem;
  problem.angle_triples = bad_triples.data();
  auto status = animlod::validate_motion_refit_problem(problem);
  REQUIRE_FALSE(status);
  CHECK(status.message == "angle_triples[0]: point 41 is outside [0, 9)");

  problem = f.problem;
  std::vector<double> lengths = f.key_lengths;
  lengths[2] = 0.0;
  problem.key_lengths = lengths.data();
  status = animlod::validate_motion_refit_problem(problem);
  REQUIRE_FALSE(status);
  CHECK(status.message.rfind("key_lengths[2]", 0) == 0);

  std::vector<double> original = f.key, fallback = f.key;
  original[3 * 4 + 1] = std::nan("");
  MotionRefitResult result;
  status = animlod::motion_refit_solve(f.problem, original.data(), fallback.data(), nullptr, 1, {}, result);
  REQUIRE_FALSE(status);
  CHECK(status.message == "original: frame 0, point 4 is not finite");

  MotionRefitOptions options;
  options.chunk_frames = 0;
  status = animlod::motion_refit_solve(f.problem, f.key.data(), f.key.data(), nullptr, 1, options, result);
  REQUIRE_FALSE(status);
  CHECK(status.message == "chunk_frames: must be at least 1, got 0");
}

TEST_CASE("motion refit: a flat group is held by its child's height over the base plane") {
  // Parent 1 with children 2, 4 (the base) and 3 in one plane z = 0: distances alone pin 3 out of
  // that plane only to second order; the flat quad's row is its height change over L. Child 3
  // keeps its distance to base child 4 (with which it spans the larger triangle), not to 2.
  std::vector<double> key = {0, 0, 0,  0, 2, 0,  1, 2, 0,  -1, 2.1, 0,  0.1, 3, 0};
  std::vector<int32_t> pairs = {1, 0, 2, 1, 3, 1, 4, 1, 4, 2, 3, 4};
  const std::vector<double> lengths = pair_lengths(key, pairs);
  std::vector<int32_t> quad = {1, 2, 4, 3};
  const std::vector<double> volume = {0.0};
  const std::vector<double> base_area = {1.0};  // |(1, 0, 0) x (0.1, 1, 0)|
  MotionRefitProblem problem;
  problem.point_count = 5;
  problem.length_pairs = pairs.data();
  problem.key_lengths = lengths.data();
  problem.length_pair_count = lengths.size();
  problem.flat_quads = quad.data();
  problem.flat_volumes = volume.data();
  problem.flat_areas = base_area.data();
  problem.flat_quad_count = 1;
  problem.length_scale = 3.0;
  const size_t p = 5, m = animlod::motion_refit_equality_count(problem);
  REQUIRE(m == lengths.size() + 1);
  std::vector<double> values(m), jacobian(m * 3 * p), plus_values(m), minus_values(m);
  REQUIRE(animlod::motion_refit_equalities(problem, key.data(), 1, values.data(), nullptr));
  for (double v : values) CHECK(std::abs(v) < 1e-12);
  // Lifting the child by h changes its row by h / L.
  std::vector<double> lifted = key;
  lifted[3 * 3 + 2] += 0.03;
  REQUIRE(animlod::motion_refit_equalities(problem, lifted.data(), 1, values.data(), jacobian.data()));
  CHECK(std::abs(values[m - 1]) == doctest::Approx(0.03 / 3.0));
  const double h = 1e-6;
  for (size_t i = 3; i < 3 * p; ++i) {
    std::vector<double> plus = lifted, minus = lifted;
    plus[i] += h;
    minus[i] -= h;
    animlod::detail::refit_equalities_frame(problem, plus.data(), plus_values.data(), nullptr);
    animlod::detail::refit_equalities_frame(problem, minus.data(), minus_values.data(), nullptr);
    for (size_t r = 0; r < m; ++r)
      CHECK(jacobian[r * 3 * p + i] == doctest::Approx((plus_values[r] - minus_values[r]) / (2 * h)).scale(1.0));
  }
  check_rows_read_their_points(problem, jacobian);
  // A hard solve pulled out of the plane by the original positions keeps the group's shape.
  std::vector<double> original = lifted;
  original[3 * 2 + 2] -= 0.02;
  MotionRefitResult result;
  REQUIRE(animlod::motion_refit_solve(problem, original.data(), key.data(), nullptr, 1, {}, result));
  CHECK(result.failures.empty());
  REQUIRE(animlod::motion_refit_equalities(problem, result.positions.data(), 1, values.data(), nullptr));
  for (double v : values) CHECK(std::abs(v) < 1e-8);
  // The distance the flat quad replaced (child 3 to base child 2) holds too: the shape is rigid.
  const std::vector<int32_t> replaced = {3, 2};
  CHECK(pair_lengths(result.positions, replaced)[0] == doctest::Approx(pair_lengths(key, replaced)[0]).epsilon(1e-7));
}
