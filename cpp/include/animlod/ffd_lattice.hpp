// Rational free-form deformation (RFFD) with tensor-product Bernstein lattices of any size, as
// used for facial animation by regions (seeds/004, Section 3.2.2; Sederberg and Parry 1986 for
// FFD, Kalra et al. 1992 for its rational form with weighted control points).
//
// A lattice spans a box (a parallelepiped) X(s, t, u) = origin + s S + t T + u U with local
// coordinates s, t, u in [0, 1]. It has l x m x n control points (l, m, n >= 2; the Bernstein
// degree along an axis is its size minus one) stored flat, control point (i, j, k) at index
// (i * m + j) * n + k, and one weight w_ijk > 0 per control point. A point with local
// coordinates (s, t, u) goes to
//
//   X(s, t, u) = sum_ijk w_ijk B_i^{l-1}(s) B_j^{m-1}(t) B_k^{n-1}(u) P_ijk
//              / sum_ijk w_ijk B_i^{l-1}(s) B_j^{m-1}(t) B_k^{n-1}(u),
//
// B_i^d(x) = C(d, i) x^i (1 - x)^(d - i). With every weight 1 the denominator is 1 and this is
// the plain Bezier FFD; on a regular lattice (P_ijk = origin + i/(l-1) S + j/(m-1) T + k/(n-1) U)
// the plain FFD is the identity (linear precision). For fixed weights X is linear in the control
// points, so a deformation can be written as displacements of the control points:
// p' = p + X_delta(s, t, u), which leaves every point in place at zero displacement whatever the
// weights (ffd_displace). Local coordinates outside [0, 1] are clamped: a point outside the box
// moves as the nearest point of the box does.
#pragma once

#include <cstddef>
#include <cstdint>

#include "animlod/status.hpp"

namespace animlod {

// Largest number of control points along one axis (Bernstein degree 15).
inline constexpr size_t kMaxLatticeSize = 16;

// The box a lattice spans, asset units.
struct LatticeBox {
  double origin[3] = {0.0, 0.0, 0.0};
  double axes[3][3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};  // S, T, U edge vectors
};

// One lattice: its size and (non-owning) control points and weights.
struct LatticeView {
  size_t size[3] = {3, 3, 3};              // l, m, n control points along S, T, U, each in [2, 16]
  const double* control_points = nullptr;  // (l * m * n, 3) positions (or displacements)
  const double* weights = nullptr;         // (l * m * n,) > 0, or null for all ones (plain Bezier FFD)
};

// Several lattices for one call of ffd_displace; lattice r owns the control points from
// sum_{q<r} l_q m_q n_q on, in lattice order.
struct LatticeSetView {
  size_t lattice_count = 0;                // R
  const int32_t* sizes = nullptr;          // (R, 3) l, m, n of each lattice, each in [2, 16]
  const double* displacements = nullptr;   // (F, C, 3) control-point displacements per frame, C = sum l m n
  const double* weights = nullptr;         // (C,) > 0, or null for all ones
  size_t frame_count = 1;                  // F
};

// Local coordinates of points in a box: solves p = origin + s S + t T + u U for every point.
//
// points (V, 3) float32, asset units; out_local (V, 3) float32 (s, t, u), caller-owned, not
// clamped (1 beyond [0, 1] means outside the box).
// Errors: an axis of zero length (naming it: "lattice box: axis U is degenerate ..."), axes
// that lie in one plane (a flat box), a non-finite box value or point (naming the point). On
// error out_local is unspecified.
Status ffd_local_coordinates(const LatticeBox& box, const float* points, size_t point_count, float* out_local);

// Evaluates the rational Bezier volume X(s, t, u) of `lattice` at local coordinates.
//
// local (V, 3) float32, clamped to [0, 1]; out (V, 3) float32, caller-owned.
// Errors: a size outside [2, 16], a null control_points, a weight that is not finite and > 0
// (naming the control point), a non-finite local coordinate (naming the point).
Status ffd_evaluate(const LatticeView& lattice, const float* local, size_t point_count, float* out);

// The runtime deformation of a set of lattices, frame by frame: every vertex v with
// vertex_lattice[v] = r >= 0 moves by the rational FFD of lattice r's displacements at local[v],
// out[f, v] = rest[v] + X_delta_r(local[v]) with frame f's displacements; a vertex with
// vertex_lattice[v] = -1 stays at rest[v].
//
// rest (V, 3) float32; local (V, 3) float32 (clamped to [0, 1]); vertex_lattice (V,) int32;
// out (F, V, 3) float32, caller-owned. Cost O(F V l m n).
// Errors: a size outside [2, 16], null displacements with lattices present, a weight that is not
// finite and > 0, a vertex_lattice entry outside [-1, R) (naming the vertex). Displacements and
// positions are not checked for finiteness (a runtime path: NaN in, NaN out).
Status ffd_displace(const LatticeSetView& lattices, const float* rest, const float* local,
                    const int32_t* vertex_lattice, size_t vertex_count, float* out);

// How ffd_fit regularises the correction Q = P - prior of the control points. Both weights are
// relative to the data: a weight w stands for w * V / (l m n) (V points), the average weight a
// control point gets from the data, so that well-determined control points barely feel them.
struct FfdFitOptions {
  // Squared second differences of Q along every lattice line (size >= 3): the correction is
  // smooth. Trilinear corrections cost nothing, so a 2x2x2 fit is unaffected.
  double smoothness = 1e-3;
  // Squared Q: control points the points hardly determine (a thin region, an empty corner of
  // the box) stay at the prior instead of taking huge values that cancel at the points.
  double ridge = 1e-3;
};

// Least-squares fit of a lattice to target positions: the control points P (l m n, 3) that
// minimise sum_v |X_P(local[v]) - target[v]|^2 for fixed weights (the FFD is linear in P), plus
// the regularisation of `options` on P - prior. Used to turn a displacement field into the
// control displacements of an MPA (prior: the field at the control points), and to replace a
// region's 3x3x3 lattice by a 2x2x2 one at coarse levels (seeds/004, Section 4.2.2; prior: the
// 3x3x3 corners, which the volume interpolates).
//
// size: l, m, n in [2, 16]; weights (l m n,) > 0 or null; local (V, 3) float32, clamped to
// [0, 1]; targets (V, 3) float32; prior (l m n, 3) float64 or null for zeros;
// out_control_points (l m n, 3) float64, caller-owned. Without regularisation (both weights 0),
// where the points do not determine every control point the correction of least norm is
// returned (complete orthogonal decomposition).
// Errors: a size outside [2, 16], no points, a bad weight, a negative or non-finite
// regularisation weight, a non-finite local coordinate, target or prior (naming the point).
Status ffd_fit(const size_t size[3], const double* weights, const float* local, const float* targets,
               size_t point_count, const double* prior, double* out_control_points,
               const FfdFitOptions& options = {});

}  // namespace animlod
