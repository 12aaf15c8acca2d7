// Per-frame pieces of the motion LoD re-fit (motion_refit_terms.cpp), shared with the solver
// (motion_refit_solve.cpp). One frame's positions are (P, 3) doubles; Jacobians are dense rows
// over all 3P coordinates (root included, then zeroed by the callers that need it).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/motion_refit.hpp"

namespace animlod::detail {

// Stopping rules of the inner Newton solves (free points, pendant trees): per solve and
// evaluation at most kNewtonIterations steps of at most kNewtonHalvings line-search halvings; a
// step shorter than kNewtonStep (a fraction of L, or radians), or a Newton decrement below
// kNewtonDecrement of the value, ends it: at quadratic convergence the gradient left is then far
// below what SLSQP's stopping rule can see.
constexpr int kNewtonIterations = 50;
constexpr int kNewtonHalvings = 40;
constexpr double kNewtonStep = 1e-13;
constexpr double kNewtonDecrement = 1e-15;

// flags[k] = value for every point k of the (count, width) index rows (a term's points).
inline void set_points_of(const int32_t* rows, size_t count, size_t width, uint8_t value,
                          std::vector<uint8_t>& flags) {
  for (size_t i = 0; i < count * width; ++i) flags[rows[i]] = value;
}

// Two unit vectors completing the unit vector u to an orthonormal basis: the tangent plane in
// which the pendant trees and the bone directions move a direction.
inline void tangent_basis(const double* u, double* e1, double* e2) {
  const int axis = std::abs(u[0]) < 0.6 ? 0 : (std::abs(u[1]) < 0.6 ? 1 : 2);
  double helper[3] = {0.0, 0.0, 0.0};
  helper[axis] = 1.0;
  const double along = helper[0] * u[0] + helper[1] * u[1] + helper[2] * u[2];
  for (int a = 0; a < 3; ++a) e1[a] = helper[a] - along * u[a];
  const double norm = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  for (int a = 0; a < 3; ++a) e1[a] /= norm;
  e2[0] = u[1] * e1[2] - u[2] * e1[1];
  e2[1] = u[2] * e1[0] - u[0] * e1[2];
  e2[2] = u[0] * e1[1] - u[1] * e1[0];
}

// E (Eq. 5) of one frame; adds nothing to the root's gradient. gradient: (P, 3) or nullptr.
double refit_objective_frame(const MotionRefitProblem& problem, const double* x, const double* original,
                             double* gradient);

// The equality rows of refit_equalities_frame, in order: one per held length, three (x, y, z)
// per coincident pair, one per flat quad; each with the points it reads.
struct EqualityRow {
  std::array<int32_t, 4> points;
  int width;  // 2 or 4
};
std::vector<EqualityRow> equality_rows(const MotionRefitProblem& problem);
// The first of coincident pair k's three rows.
inline size_t first_coincident_row(const MotionRefitProblem& problem, size_t k) {
  return problem.length_pair_count + 3 * k;
}

// Equality values (m,) and, when jacobian is not nullptr, their derivatives (m, P, 3).
void refit_equalities_frame(const MotionRefitProblem& problem, const double* x, double* values,
                            double* jacobian);

// Handedness values (Nh,) and, when jacobian is not nullptr, their derivatives (Nh, P, 3).
void refit_handedness_frame(const MotionRefitProblem& problem, const double* x, double* values,
                            double* jacobian);

// The Hessian of E at x over the non-root coordinates, n x n row-major with n = 3 (P - 1)
// (matrix must hold n * n doubles). For each squared residual w r^2 the block is
// 2 w (grad r grad r^T + r Hess r). With positive_semidefinite, each term's block is made
// positive semidefinite on its own (a length's curvature only when stretched, an angle's 9 x 9
// block with negative eigenvalues clipped to 0), so that the sum is positive definite (Ed gives
// 2 alpha / L^2 I): the solver's preconditioner. Without, the exact Hessian (for tests).
void refit_hessian_frame(const MotionRefitProblem& problem, const double* x, bool positive_semidefinite,
                         double* matrix);

// Ea's term of angle triple k at x (Eq. 8): gamma (cos - cos0)^2, its gradient over the
// triple's (parent, joint, child) coordinates and, when built with curvature, its Hessian
// 2 gamma (grad cos grad cos^T + (cos - cos0) Hess cos) block by block: a caller that holds
// only some of the three points (a free-point cluster) builds only their blocks.
class AngleTerm {
 public:
  AngleTerm(const MotionRefitProblem& problem, const double* x, size_t k, bool curvature);
  double value() const { return weight_ * residual_ * residual_; }
  void gradient(double* out) const;  // (9,)
  // The (row, column) 3 x 3 block (row-major) of the Hessian; points 0, 1, 2 are the parent,
  // the joint and the child. Needs curvature.
  void hessian_block(int row, int column, double* block) const;

 private:
  double weight_, residual_;
  double cosine_gradient_[9];
  double huu_[9], hvv_[9], huv_[9];  // cos's second derivatives in u = p - j, v = c - j
};

}  // namespace animlod::detail
