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
//   others, found by Newton's method (motion_refit_free_points.hpp);
// - the members of a rigid body (a kept joint's kept children held by a minimal rigid set,
//   under hard constraints) follow their base and the body's rotation vector, a slot of three
//   variables of its own (motion_refit_rigid_bodies.hpp);
// - a point held by a length to another that stays in the solve (a chain's joint, under hard
//   constraints) hangs from it along a direction, a slot of two variables
//   (motion_refit_bone_directions.hpp).
// The variables are the slots' in order: three per point that stays a variable, three per
// rigid body (two for one along a line), two per direction.
// The reduced problem has the same minima as the full one; the map from reduced to full
// positions is differentiated exactly (chain rule; a free point adds nothing, as E's derivative
// with respect to it is zero at its minimum), so gradients and Jacobians stay analytic:
// reduce_rows accumulates in reverse from each placed point to the point it is placed from.
// A full point depends on one slot or several (a body's member on its base's slots and its
// body's; a tree hanging from a member on the same; a chain's point on its parent's and its own
// direction's), kept for reduce_matrix as links: (slot, 3 x 3 derivative, its third column zero
// for a direction).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/motion_refit.hpp"
#include "motion_refit_bone_directions.hpp"
#include "motion_refit_free_points.hpp"
#include "motion_refit_pendant_trees.hpp"
#include "motion_refit_rigid_bodies.hpp"

namespace animlod::detail {

class PointReduction {
 public:
  // eliminate switches the reductions (off: identity, every non-root point a variable, in
  // order); coincident points are substituted, trees placed, rigid groups made bodies and held
  // lengths made directions only under hard constraints, bodies only with `rigid_bodies` too,
  // directions only with `bone_directions`.
  PointReduction(const MotionRefitProblem& problem, bool hard_constraints, bool eliminate, bool rigid_bodies,
                 bool bone_directions);

  // n: the variables of the reduced problem (the slots' widths summed).
  size_t variable_count() const { return variable_count_; }
  // (m,) 1 for the equality rows (motion_refit_equalities) the reduced problem keeps; (Nh,)
  // the same for the handed groups (motion_refit_handedness).
  const std::vector<uint8_t>& kept_equalities() const { return kept_equalities_; }
  size_t kept_equality_count() const { return kept_equality_count_; }
  const std::vector<uint8_t>& kept_handed() const { return kept_handed_; }
  size_t kept_handed_count() const { return kept_handed_count_; }

  // The start of a solve, x (P, 3): where the free points start their minimisation in every
  // fill until the next call (see FreePointClusters::set_start), the shape of every rigid
  // body (its slot's zero is x's orientation) and the chart of every direction (its zero is x's
  // direction).
  void set_start(const double* x, const double* original);
  // Full positions x (P, 3) from the variables y (n,); the root is original's. Remembers the
  // placements' derivatives for the reduce_* calls that follow.
  void fill(const double* y, const double* original, double* x);
  // The variables (n,) of full positions x (P, 3); a body's slot is 0 (its shape at
  // set_start's orientation), a direction's x's in its chart.
  void gather(const double* x, double* y) const;
  // Derivative rows over full positions (count, P, 3) to rows over the variables (count, n),
  // at the last fill.
  void reduce_rows(const double* rows, size_t count, double* out) const;
  // A matrix over the non-root coordinates (3 (P - 1))^2 to T^T M T over the variables n^2
  // (both row-major), T the derivative of fill at the last fill; the free points
  // enter through their own derivative, -M_ff^-1 M_f. (the implicit function theorem at their
  // minimum), which makes it the Schur complement of M's free block.
  void reduce_matrix(const double* full, double* out);

 private:
  using Matrix3 = std::array<double, 9>;
  // The point whose links point k's are built from (its substitute, body base, direction's
  // parent, tree or leaf anchor; -1 for a variable, the root and free points), and the links in
  // an order where that point comes first.
  int32_t link_source(size_t k) const;
  // d x_k / d x_source (3 x 3, row-major) at the last fill: a tree's or a leaf's, the identity
  // for the points that move with their source.
  const double* source_derivative(size_t k) const;
  // The slot of a body's member or a direction's point (-1 for others), and d x_k / d that
  // slot (nullptr for others).
  int32_t own_slot(size_t k) const;
  const double* own_slot_derivative(size_t k) const;
  void build_links();
  // The links' derivatives at the positions of the last fill (for reduce_matrix).
  void update_links();

  const MotionRefitProblem& problem_;
  bool hard_ = false;
  FreePointClusters free_points_;
  PendantTrees trees_;
  RigidBodies bodies_;
  BoneDirections directions_;
  size_t variable_count_ = 0;
  std::vector<int32_t> slot_offset_;  // (slots,) each slot's first variable
  std::vector<int32_t> slot_width_;   // (slots,) 3, or 2 for a direction
  std::vector<int32_t> body_slot_;    // (bodies,) slot of each body's rotation vector
  std::vector<int32_t> direction_slot_;  // (directions,) slot of each direction
  std::vector<int32_t> link_order_;   // points with links, each after its link_source
  std::vector<int32_t> link_offsets_;  // (P + 1,) CSR offsets into link_slots_ / link_blocks_
  std::vector<int32_t> link_slots_;
  std::vector<Matrix3> link_blocks_;  // d x_k / d y_slot
  std::vector<uint8_t> kept_handed_;
  size_t kept_handed_count_ = 0;
  std::vector<int32_t> index_;        // (P,) slot of a variable point, -1 otherwise
  std::vector<int32_t> substitute_;   // (P,) the point a substituted point sits at, else itself
  std::vector<int32_t> leaf_anchor_;  // (P,) p of a leaf, -1 otherwise
  std::vector<int32_t> free_index_;   // (P,) index among the free points, -1 otherwise
  size_t free_count_ = 0;
  std::vector<std::vector<int32_t>> free_blocks_;  // per cluster: its points' rows among the free ones
  // (P,) per non-root point a, the non-root points b (increasing, a included) whose block M_ab of
  // E's Hessian can be non-zero: a term of E holds both. reduce_matrix reads only these.
  std::vector<std::vector<int32_t>> coupled_;
  std::vector<double> leaf_length_;   // (P,) b of a leaf
  std::vector<uint8_t> kept_equalities_;
  size_t kept_equality_count_ = 0;
  std::vector<Matrix3> jacobians_;    // (P,) d x_k / d x_anchor of leaves at the last fill
  mutable std::vector<double> totals_;  // (P, 3) reduce_rows' accumulated derivatives
};

}  // namespace animlod::detail
