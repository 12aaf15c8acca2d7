// Points of a re-fit frame that hang from the others by held lengths alone
// (motion_refit_pendant_trees.cpp).
//
// With hard constraints, a point whose only terms are Ed and held lengths, and all but one of
// those lengths to points of the same kind further out, belongs to a pendant tree: a leg below
// a hip held in a rigid group, a finger below a hand, a head below a neck. Given its anchor (the
// point it hangs from), the tree's optimum is a minimisation of its Ed terms over the directions
// of its bones, a few variables per point with no constraint left; it is found here by Newton's
// method on those directions. SLSQP then keeps neither the tree's points nor its lengths (its
// cost per iteration grows with the cube of the variable count), and E's gradient over the
// anchor is the sum of E's gradients over the anchor and the tree's points (the tree moves with
// the anchor when its directions are held: the envelope theorem at the inner minimum). The
// leaves of motion_refit_reduction.hpp are the one-point trees, solved in closed form there.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/motion_refit.hpp"

namespace animlod::detail {

class PendantTrees {
 public:
  // Finds the trees of two or more points; none when `enabled` is false (soft lengths, or the
  // reductions switched off).
  PendantTrees(const MotionRefitProblem& problem, bool enabled);

  bool contains(size_t point) const { return anchor_of_[point] >= 0; }
  // The point a tree point's tree hangs from (never itself a tree point).
  int32_t anchor(size_t point) const { return anchor_of_[point]; }
  // 1 for the length pairs inside a tree (from a tree point to its parent): they hold by
  // construction and leave the equalities.
  const std::vector<uint8_t>& inner_pairs() const { return inner_pairs_; }

  // Moves every tree's points of x (P, 3) to the minimum of sum |x_k - x^o_k|^2 over their bone
  // directions, their anchors held where x has them. Each minimisation starts from the bones
  // aimed, root to tips, at the original positions (a function of the anchor alone, so that
  // the placement is too).
  void place(double* x, const double* original);
  // d x_k / d x_anchor (3 x 3, row-major) of tree point k at the last place().
  const double* derivative(size_t point) const { return jacobians_[point].data(); }

 private:
  struct Tree {
    int32_t anchor = -1;
    std::vector<int32_t> points;   // parents before children
    std::vector<int32_t> parent;   // index into points, -1 for the anchor
    std::vector<double> length;    // the held length to the parent
    std::vector<uint8_t> below;    // (n, n) below[k * n + i]: point i is in k's subtree (k included)
    std::vector<int32_t> size;     // points in each subtree
  };
  void place_tree(const Tree& tree, double* x, const double* original);

  using Matrix3 = std::array<double, 9>;
  std::vector<Tree> trees_;
  std::vector<int32_t> anchor_of_;   // (P,) -1 for points outside the trees
  std::vector<uint8_t> inner_pairs_;  // (Np,)
  std::vector<Matrix3> jacobians_;    // (P,)
};

}  // namespace animlod::detail
