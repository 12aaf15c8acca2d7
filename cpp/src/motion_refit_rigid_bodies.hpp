// Rigid groups of a re-fit frame as rigid bodies (motion_refit_rigid_bodies.cpp).
//
// A kept joint with two or more kept children moves them as one rigid body in the output
// skeleton, so objective.py holds a minimal rigid set of lengths (and flat groups' heights)
// among them: 3k - 3 equalities for a joint and its k children, 3k variables. Under hard
// constraints their feasible positions are exactly the rigid motions of the start's shape that
// keep the joint where it is, so the body's members can be written as x_k = x_base + R(w) d_k
// (d_k = x_k - x_base at the start, R the rotation by the vector w): 3 variables instead of 3k,
// and none of the group's equalities, which hold by construction (a rotation keeps distances,
// heights and handedness). SLSQP's cost per iteration grows with the cube of the variable
// count and with the equality count times the variables squared, and a clip with fingers has a
// body per hand, another at the hips and one at the chest. The minima are the same.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/motion_refit.hpp"

namespace animlod::detail {

class RigidBodies {
 public:
  // Finds the bodies (none when `enabled` is false). `excluded` (P,): points that may be
  // neither a base nor a member (coincident pairs, pendant trees). A body is a point p and the
  // set C of points tied to it as the child side of a held length that are tied to another point
  // of C too, when the lengths and flat heights among them number 3 |C| - 3 (the count of a
  // minimal rigid set). A point is a member of at most one body; a body whose base is a member
  // of another comes after it in order().
  RigidBodies(const MotionRefitProblem& problem, const std::vector<uint8_t>& excluded, bool enabled);

  size_t count() const { return bases_.size(); }
  // Bodies in an order where every base is placed before its body (a base is the root, a
  // variable, or a member of an earlier body).
  const std::vector<int32_t>& order() const { return order_; }
  int32_t base(size_t body) const { return bases_[body]; }
  const std::vector<int32_t>& members(size_t body) const { return members_[body]; }
  // Its variables: 3 (a rotation vector), or 2 for a body whose held lengths put its members
  // along one line through its base (within about 3 degrees: a twist joint on its parent's bone
  // beside the next joint), which turns about the two axes across the line only. A turn about
  // the line costs nothing in E (or next to nothing), and SLSQP crawled along it: 66-108
  // evaluations per frame on a rig with Unreal-style twist joints, where 2-35 without bodies.
  int width(size_t body) const { return along_a_line_[body] ? 2 : 3; }
  // The body point k is a member of, -1 otherwise (a base only is not a member).
  int32_t body_of(size_t point) const { return body_of_[point]; }
  // (m,) 1 for equality rows (motion_refit_equalities order) held by a body; (Nh,) the same
  // for handed groups.
  const std::vector<uint8_t>& inner_equalities() const { return inner_equalities_; }
  const std::vector<uint8_t>& inner_handed() const { return inner_handed_; }

  // The shape every body keeps until the next call: d_k = x_k - x_base at x (P, 3), once the
  // members are moved onto their group's lengths and heights where x is off them (an
  // infeasible start: Gauss-Newton steps of least norm, bases held).
  void set_start(const double* x);
  // Members of `body` at x_base + R(w) d_k in x (P, 3), its base already placed there; w the
  // body's width() variables (for a body along a line, w = u0 a0 + u1 a1, a0 and a1 across the
  // line at set_start). Remembers d x_k / d variables for derivative().
  void place(size_t body, const double* variables, double* x);
  // d x_k / d the body's variables (3 x 3, row-major; the third column zero for a body along a
  // line) of member k at the last place().
  const double* derivative(size_t point) const { return jacobians_[point].data(); }

 private:
  using Matrix3 = std::array<double, 9>;
  // Moves the members in shape_ until every body's rows hold (see set_start).
  void make_rigid();

  const MotionRefitProblem& problem_;
  std::vector<int32_t> bases_;
  std::vector<std::vector<int32_t>> members_;
  std::vector<int32_t> order_;
  std::vector<uint8_t> along_a_line_;  // (bodies,) 1 for a body of width 2
  std::vector<Matrix3> turn_bases_;    // (bodies,) the axes across its line (columns 0, 1)
  std::vector<int32_t> body_of_;      // (P,)
  std::vector<uint8_t> inner_equalities_;
  std::vector<uint8_t> inner_handed_;
  std::vector<size_t> held_rows_;     // the equality rows the bodies hold
  std::vector<double> shape_;         // (P, 3) set_start's positions, made rigid
  std::vector<double> values_, jacobian_;
  std::vector<double> offsets_;       // (P, 3) d_k of members
  std::vector<Matrix3> jacobians_;    // (P,)
};

}  // namespace animlod::detail
