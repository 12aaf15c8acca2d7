// Points of a re-fit frame that need no variables of their own (motion_refit_reduction.cpp).
//
// SLSQP's cost per iteration grows with the cube of the variable count, so the solve leaves out
// points whose optimum follows exactly from others':
// - a point tied to another by a coincident pair (zero key length) under hard constraints is at
//   that point (x_a = x_b holds exactly), so it is substituted;
// - a leaf (a point in exactly one term of E, a held length to another point p) lies on the ray
//   from x_p to its original position, at the held length b with hard constraints, or at
//   r = (alpha d + beta b) / (alpha + beta) without (d = |x^o - x_p|): its Ed and Es terms are
//   then minimal given x_p, in closed form;
// - a point of a pendant tree (held lengths only, hanging from one other point, under hard
//   constraints) is at the minimum of its tree's Ed terms given that point, found by Newton's
//   method over the bone directions (motion_refit_pendant_trees.hpp);
// - a free point (in no held length, coincident pair or handed group: a frozen joint or an end
//   site below one at a coarse level) is at the minimum of its Ed and angle terms given the
//   others, found by Newton's method (motion_refit_free_points.hpp).
// The reduced problem has the same minima as the full one; the map from reduced to full
// positions is differentiated exactly (chain rule; a free point adds nothing, as E's derivative
// with respect to it is zero at its minimum), so gradients and Jacobians stay analytic.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/motion_refit.hpp"
#include "motion_refit_free_points.hpp"
#include "motion_refit_pendant_trees.hpp"

namespace animlod::detail {

class PointReduction {
 public:
  // eliminate switches the reductions (off: identity, every non-root point a variable, in
  // order); coincident points are substituted only under hard constraints.
  PointReduction(const MotionRefitProblem& problem, bool hard_constraints, bool eliminate);

  size_t reduced_points() const { return reduced_points_; }  // P_r: points that stay variables
  // (m,) 1 for the equality rows (motion_refit_equalities) the reduced problem keeps.
  const std::vector<uint8_t>& kept_equalities() const { return kept_equalities_; }
  size_t kept_equality_count() const { return kept_equality_count_; }

  // Where the free points start their minimisation in every fill until the next call (see
  // FreePointClusters::set_start): the free points of x (P, 3).
  void set_free_start(const double* x, const double* original) { free_points_.set_start(x, original); }
  // Full positions x (P, 3) from the reduced ones y (P_r, 3); the root is original's. Remembers
  // the leaves' and the trees' Jacobians for the reduce_* calls that follow.
  void fill(const double* y, const double* original, double* x);
  // The reduced positions (P_r, 3) of full positions x (P, 3).
  void gather(const double* x, double* y) const;
  // Derivative rows over full positions (count, P, 3) to rows over reduced ones (count, P_r, 3),
  // at the last fill.
  void reduce_rows(const double* rows, size_t count, double* out) const;
  // A matrix over the non-root coordinates (3 (P - 1))^2 to T^T M T over the reduced ones
  // (3 P_r)^2 (both row-major), T the derivative of fill at the last fill; the free points
  // enter through their own derivative, -M_ff^-1 M_f. (the implicit function theorem at their
  // minimum), which makes it the Schur complement of M's free block.
  void reduce_matrix(const double* full, double* out) const;

 private:
  using Matrix3 = std::array<double, 9>;
  // Where full point k's derivative goes: reduced point (-1: none, the root) and the 3 x 3
  // derivative of x_k with respect to it (identity unless k is a leaf or a tree point, whose
  // derivatives go to its anchor).
  int32_t target(size_t k) const;
  const double* derivative(size_t k) const;

  const MotionRefitProblem& problem_;
  bool hard_ = false;
  FreePointClusters free_points_;
  PendantTrees trees_;
  size_t reduced_points_ = 0;
  std::vector<int32_t> index_;        // (P,) reduced index of a variable point, -1 otherwise
  std::vector<int32_t> substitute_;   // (P,) the point a substituted point sits at, else itself
  std::vector<int32_t> leaf_anchor_;  // (P,) p of a leaf, -1 otherwise
  std::vector<int32_t> free_index_;   // (P,) index among the free points, -1 otherwise
  size_t free_count_ = 0;
  std::vector<double> leaf_length_;   // (P,) b of a leaf
  std::vector<uint8_t> kept_equalities_;
  size_t kept_equality_count_ = 0;
  std::vector<Matrix3> jacobians_;    // (P,) d x_k / d x_anchor of leaves at the last fill
};

}  // namespace animlod::detail
