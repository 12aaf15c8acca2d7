// Held lengths of a re-fit frame as bone directions (motion_refit_bone_directions.cpp).
//
// Under hard constraints a point c held by a length b to a point p sits on the sphere of radius
// b around p, so it can be written x_c = x_p + b u(s) with two coordinates s of its direction
// u: two variables instead of three and one equality fewer, which holds by construction. SLSQP's
// cost per iteration grows with the cube of the variable count and with the equalities times
// the variables squared, and the chains between branch points (a spine, a neck, a tail, hair,
// a leg above a rigid foot) are such points, one after another. The points taken are a spanning
// forest of the held lengths the caller offers among the points that are still variables (no
// other reduction places them): each tree's first point stays a variable (or is the root),
// every other point hangs from its parent in the tree; lengths outside the forest stay
// equalities. The minima are the same.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/motion_refit.hpp"

namespace animlod::detail {

class BoneDirections {
 public:
  BoneDirections() = default;
  // Finds the forest (nothing when `enabled` is false). `candidate` (P,): points that may hang
  // from a parent or be one (the root and the points no other reduction places); `kept_pairs`
  // (Np,): 1 for the held lengths that are still equalities.
  BoneDirections(const MotionRefitProblem& problem, const std::vector<uint8_t>& candidate,
                 const std::vector<uint8_t>& kept_pairs, bool enabled);

  // The directions, every parent's before its children's (a tree's first point, the root or a
  // variable, hangs from none).
  size_t count() const { return points_.size(); }
  int32_t parent(size_t i) const { return parents_[i]; }
  // The held length pair that direction i holds.
  int32_t pair(size_t i) const { return pairs_[i]; }
  // The index of point k among the directions, -1 when it hangs from none.
  int32_t direction_of(size_t point) const { return direction_of_[point]; }

  // The chart of every direction until the next call: s = 0 is x's direction (P, 3) from the
  // parent to the point, or the original's where x has none.
  void set_start(const double* x, const double* original);
  // Direction i's point at x_parent + b u(s) in x (P, 3), its parent already placed there.
  // Remembers d x / d s for derivative().
  void place(size_t i, const double* s, double* x);
  // The coordinates s (2,) of direction i whose point and parent are at x (P, 3).
  void coordinates(size_t i, const double* x, double* s) const;
  // d x_k / d s (3 x 3, row-major, its third column zero) of hanging point k at the last place().
  const double* derivative(size_t point) const { return jacobians_[point].data(); }

 private:
  using Matrix3 = std::array<double, 9>;
  std::vector<int32_t> points_, parents_, pairs_;
  std::vector<double> lengths_;
  std::vector<int32_t> direction_of_;  // (P,)
  std::vector<Matrix3> charts_;       // per direction: u0, e1, e2 (rows)
  std::vector<Matrix3> jacobians_;    // (P,)
};

}  // namespace animlod::detail
