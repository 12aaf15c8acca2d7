// The affine / residual split of a deforming mesh (Shamir and Pascucci 2001, Section 3): the
// low-frequency motion of every frame is the least-squares affine map from a base mesh to that
// frame; the residual mesh is the frame mapped back by the inverse map, which keeps only the
// high-frequency (local) deformation.
#pragma once

#include <cstdint>
#include <vector>

#include "animlod/animated_mesh_view.hpp"
#include "animlod/status.hpp"

namespace animlod {

// The base mesh P_0 that every frame is mapped from.
enum class AffineBase {
  first,    // frame 0
  average,  // the average position of every vertex over all frames
};

struct AffineSplit {
  // (F, 3, 4) row-major, asset units: frame t ~ maps[t] * [base; 1] (Section 3,
  // A_t = P_t P_0^T (P_0 P_0^T)^-1 with P homogeneous 4 x V; the last row of A_t is (0 0 0 1)).
  std::vector<double> maps;
  // (F, V, 3) float32, asset units: residual mesh of frame t, A_t^-1 applied to frame t.
  // Applying maps[t] to residuals[t] gives frame t back (up to float rounding).
  std::vector<float> residuals;
  // (F,) 1 where the frame's least-squares map was singular or badly conditioned (a flat base,
  // or a frame collapsed to a plane) and the frame uses the translation of its centroid only.
  std::vector<uint8_t> translation_only;
};

// Computes the split of `mesh` against `base`. Cost O(F V).
//
// Errors (naming the element): no frames or vertices; a non-finite position (frame and vertex
// named). Connectivity is not looked at (faces may be null).
Status affine_split(const AnimatedMeshView& mesh, AffineBase base, AffineSplit& out);
// The split of the vertices vertices[0 .. count) of `mesh` only (indices into it, in that order:
// the residuals are (F, count, 3)), e.g. a welded mesh's points, without a copy of their frames.
Status affine_split(const AnimatedMeshView& mesh, const int32_t* vertices, size_t count, AffineBase base,
                    AffineSplit& out);

// Applies a (3, 4) row-major affine map to `count` points (count, 3) float32, writing
// (count, 3) float32 into `out` (may not alias `points`).
void apply_affine(const double* map, const float* points, size_t count, float* out);

}  // namespace animlod
