// The small figure the motion re-fit tests solve (test_motion_refit*.cpp), E at a point, and
// the checks those tests share (reduced gradients against finite differences, held lengths).
#pragma once

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "../../cpp/src/motion_refit_detail.hpp"
#include "../../cpp/src/motion_refit_reduction.hpp"
#include "animlod/motion_refit.hpp"

// |x_a - x_b| of every pair (a, b) of `pairs` at positions `x` (P, 3).
inline std::vector<double> pair_lengths(const std::vector<double>& x, const std::vector<int32_t>& pairs) {
  std::vector<double> lengths;
  for (size_t k = 0; k < pairs.size() / 2; ++k) {
    double sum = 0.0;
    for (int a = 0; a < 3; ++a) {
      const double d = x[3 * pairs[2 * k] + a] - x[3 * pairs[2 * k + 1] + a];
      sum += d * d;
    }
    lengths.push_back(std::sqrt(sum));
  }
  return lengths;
}

// `key` (P, 3) with N(0, scale) noise on every coordinate but the root's.
inline std::vector<double> perturbed_positions(const std::vector<double>& key, unsigned seed, double scale) {
  std::mt19937 random(seed);
  std::normal_distribution<double> normal(0.0, scale);
  std::vector<double> x = key;
  for (size_t i = 3; i < x.size(); ++i) x[i] += normal(random);
  return x;
}

// A figure held by lengths alone: key positions (P, 3), its length pairs and their key lengths.
struct LengthFigure {
  std::vector<double> key;
  std::vector<int32_t> pairs;
  std::vector<double> key_lengths;
  animlod::MotionRefitProblem problem;

  LengthFigure(std::vector<double> key_positions, std::vector<int32_t> length_pairs, double length_scale)
      : key(std::move(key_positions)), pairs(std::move(length_pairs)), key_lengths(pair_lengths(key, pairs)) {
    problem.point_count = key.size() / 3;
    problem.length_pairs = pairs.data();
    problem.key_lengths = key_lengths.data();
    problem.length_pair_count = key_lengths.size();
    problem.length_scale = length_scale;
  }
  LengthFigure(const LengthFigure&) = delete;  // problem points into the vectors
  LengthFigure& operator=(const LengthFigure&) = delete;

  std::vector<double> perturbed(unsigned seed, double scale) const { return perturbed_positions(key, seed, scale); }
};

// The solve of `frames` perturbations of `key` (seeds first_seed, ...; the key posture as the
// feasible fallback), with and without eliminate_points, on one thread; checks that both solve
// every frame and end at the same E.
struct EliminationRun {
  animlod::MotionRefitResult with, without;  // every point a variable / points eliminated
};
inline EliminationRun solve_with_and_without_elimination(const animlod::MotionRefitProblem& problem,
                                                         const std::vector<double>& key, unsigned first_seed,
                                                         double scale, size_t frames) {
  std::vector<double> original, fallback;
  for (size_t t = 0; t < frames; ++t) {
    const std::vector<double> o = perturbed_positions(key, first_seed + static_cast<unsigned>(t), scale);
    original.insert(original.end(), o.begin(), o.end());
    fallback.insert(fallback.end(), key.begin(), key.end());
  }
  animlod::MotionRefitOptions options;
  options.ftol_rel = 1e-12;
  options.threads = 1;
  EliminationRun run;
  options.eliminate_points = false;
  REQUIRE(animlod::motion_refit_solve(problem, original.data(), fallback.data(), nullptr, frames, options, run.with));
  options.eliminate_points = true;
  REQUIRE(
      animlod::motion_refit_solve(problem, original.data(), fallback.data(), nullptr, frames, options, run.without));
  CHECK(run.with.failures.empty());
  CHECK(run.without.failures.empty());
  for (size_t t = 0; t < frames; ++t) CHECK(run.without.values[t] == doctest::Approx(run.with.values[t]).epsilon(1e-6));
  return run;
}

// A small figure: root 0, a spine 1-2, a frozen joint 3 with child 4, a coincident point 5 on 1,
// and three children 6, 7, 8 of 2 spanning a volume (a handed group).
struct Figure {
  std::vector<double> key = {0, 0, 0,  0, 1, 0,  0, 2, 0,  1, 2, 0,  2, 2.2, 0,  0, 1, 0,
                             -0.5, 2.5, 0.2,  0.5, 2.5, 0.1,  0, 2.6, -0.6};
  std::vector<int32_t> pairs = {1, 0, 2, 1, 6, 2, 7, 2, 8, 2, 7, 6, 8, 6, 8, 7};
  std::vector<double> key_lengths;
  std::vector<int32_t> coincident = {5, 1};
  std::vector<int32_t> quads = {2, 6, 7, 8};
  std::vector<double> key_volumes;
  std::vector<int32_t> triples = {2, 3, 4};
  std::vector<double> key_cosines = {-0.9};
  animlod::MotionRefitProblem problem;

  Figure() {
    key_lengths = pair_lengths(key, pairs);
    problem.point_count = 9;
    problem.length_pairs = pairs.data();
    problem.key_lengths = key_lengths.data();
    problem.length_pair_count = key_lengths.size();
    problem.coincident_pairs = coincident.data();
    problem.coincident_pair_count = 1;
    problem.handed_quads = quads.data();
    problem.handed_quad_count = 1;
    problem.angle_triples = triples.data();
    problem.key_cosines = key_cosines.data();
    problem.angle_triple_count = 1;
    problem.length_scale = 2.0;
    std::vector<double> volume(1);
    key_volumes = {1.0};  // placeholder with the right size, replaced below
    problem.key_volumes = key_volumes.data();
    // The key volume's sign: the handedness value is -sign(V0) V / L^3 <= 0 at the key.
    animlod::detail::refit_handedness_frame(problem, key.data(), volume.data(), nullptr);
    key_volumes[0] = volume[0] < 0.0 ? 1.0 : -1.0;
  }

  std::vector<double> perturbed(unsigned seed, double scale) const { return perturbed_positions(key, seed, scale); }
};

inline double objective_at(const animlod::MotionRefitProblem& p, const std::vector<double>& x, const std::vector<double>& o) {
  return animlod::detail::refit_objective_frame(p, x.data(), o.data(), nullptr);
}

// E at the full positions of the reduced variables y, and its gradient over y.
inline double reduced_energy(animlod::detail::PointReduction& reduction, const animlod::MotionRefitProblem& problem,
                             const std::vector<double>& y, const std::vector<double>& original,
                             std::vector<double>& gradient) {
  std::vector<double> x(original), full(original.size());
  reduction.fill(y.data(), original.data(), x.data());
  const double value = animlod::detail::refit_objective_frame(problem, x.data(), original.data(), full.data());
  reduction.reduce_rows(full.data(), 1, gradient.data());
  return value;
}

// The central difference of reduced_energy along y[i] with step h; g_plus and g_minus receive
// the reduced gradients at y + h e_i and y - h e_i.
inline double reduced_energy_slope(animlod::detail::PointReduction& reduction,
                                   const animlod::MotionRefitProblem& problem, const std::vector<double>& y,
                                   const std::vector<double>& original, size_t i, double h,
                                   std::vector<double>& g_plus, std::vector<double>& g_minus) {
  std::vector<double> plus = y, minus = y;
  plus[i] += h;
  minus[i] -= h;
  return (reduced_energy(reduction, problem, plus, original, g_plus) -
          reduced_energy(reduction, problem, minus, original, g_minus)) /
         (2 * h);
}

// Checks the reduced gradient at y against central differences (step h) along y[first], ...
inline void check_reduced_gradient(animlod::detail::PointReduction& reduction,
                                   const animlod::MotionRefitProblem& problem, const std::vector<double>& y,
                                   const std::vector<double>& original, size_t first, double h, double epsilon) {
  std::vector<double> gradient(y.size()), g_plus(y.size()), g_minus(y.size());
  reduced_energy(reduction, problem, y, original, gradient);
  for (size_t i = first; i < y.size(); ++i) {
    const double numeric = reduced_energy_slope(reduction, problem, y, original, i, h, g_plus, g_minus);
    CHECK(gradient[i] == doctest::Approx(numeric).epsilon(epsilon).scale(1.0));
  }
}

// Checks that every frame of `positions` (frames, P, 3) holds the pairs' key lengths within
// `tolerance`.
inline void check_lengths_held(const std::vector<double>& positions, size_t point_count,
                               const std::vector<int32_t>& pairs, const std::vector<double>& key_lengths,
                               double tolerance) {
  const size_t stride = 3 * point_count;
  for (size_t t = 0; t < positions.size() / stride; ++t) {
    const std::vector<double> x(positions.begin() + static_cast<long>(t * stride),
                                positions.begin() + static_cast<long>((t + 1) * stride));
    const std::vector<double> lengths = pair_lengths(x, pairs);
    for (size_t k = 0; k < lengths.size(); ++k) CHECK(std::abs(lengths[k] - key_lengths[k]) < tolerance);
  }
}
