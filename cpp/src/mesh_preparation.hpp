// Turns any indexed triangle mesh into what an edge-collapse engine can work on: one manifold
// surface of "points" (welded positions) whose corners still know their input vertex
// ("wedge"), so that attribute seams (UV, normal, material borders) survive simplification.
//
// The steps, in the spirit of meshoptimizer's position remap + vertex kinds:
//   1. weld: input vertices that are equal in every frame, in their position-following
//      attributes and in their skin become one point (UV-seam and flat-shading copies);
//   2. drop faces that are degenerate after welding, and repeated faces;
//   3. cut the surface into manifold pieces: faces are joined across an edge only in pairs of
//      opposite directions, and a point whose faces form several fans (a bow tie) becomes one
//      point per fan. Such split points are locked, so the pieces stay stitched;
//   4. merge wedges of one point that carry equal attributes in the same face group: only
//      real attribute differences make seams.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/animated_mesh_view.hpp"

namespace animlod::detail {

// Per-vertex data that decides what may weld (all optional; null means "not given").
struct WeldInput {
  const float* position_attributes = nullptr;  // (V, B) values that move with the position
  size_t position_attribute_count = 0;         // B
  const float* attributes = nullptr;           // (V, A) values that may differ across a seam
  size_t attribute_count = 0;                  // A
  const int32_t* skin_joints = nullptr;        // (V, K)
  const float* skin_weights = nullptr;         // (V, K)
  size_t influence_count = 0;                  // K
  const int32_t* face_groups = nullptr;        // (M,) material/primitive of each face
  bool weld = true;                            // false: every input vertex is its own point
  // true: a face repeated in the reverse turn (a two-sided sheet, as exporters write double-
  // sided cloth or leaves) leaves the surface and is recorded in mirror_sources; false: both
  // stay, and the non-manifold cut separates and locks them.
  bool mirror_two_sided = false;
};

struct PreparedMesh {
  // Points: P manifold vertices. Point p stands for input vertex point_source[p] (the lowest
  // input index welded into it); split copies of one position share that source.
  std::vector<int32_t> point_source;  // (P,)
  std::vector<uint8_t> point_split;   // (P,) 1 for points cut apart at a non-manifold spot
  // Faces that survive steps 2-3, in input order.
  std::vector<int32_t> faces;          // (M', 3) point indices, manifold, consistently oriented
  std::vector<int32_t> corner_wedges;  // (M', 3) input vertex standing for each corner (after step 4)
  std::vector<int32_t> face_sources;   // (M',) input face index
  // (M',) the input face that repeats each face in the reverse turn (WeldInput::mirror_two_sided),
  // -1 for none; empty when no face has one.
  std::vector<int32_t> mirror_sources;
  // (K, 2) the mirrors' input vertices, each with the input vertex of its face's front at the
  // same point: a vertex only mirrors use maps where its front counterpart maps.
  std::vector<int32_t> mirror_vertices;
  // (M', 3) the corner whose side runs opposite corner c's (a corner's side runs from its point
  // to the next corner's in the face), -1 on a border: the surface's edges, as OpenMesh's
  // add_face pairs them. Empty when step 3 found an edge with several sides one way or an
  // unpaired opposite pair (then only add_face's own search gives that pairing).
  std::vector<int32_t> side_partners;
  std::vector<int32_t> wedge_point;    // (V,) a point of each input vertex, -1 when unreferenced
  std::vector<int32_t> wedge_representative;  // (V,) the wedge each input vertex merged into (step 4)
  // What was done, for reports.
  size_t degenerate_faces = 0;   // faces dropped because two corners are one point
  size_t duplicate_faces = 0;    // faces dropped because an earlier face has the same corners
  size_t mirrored_faces = 0;     // faces that left the surface as the reverse of an earlier one
  size_t welded_vertices = 0;    // referenced input vertices that share a point with a lower one
  size_t split_points = 0;       // extra points made by cutting non-manifold spots
  size_t seam_points = 0;        // points with more than one wedge
  size_t unreferenced_vertices = 0;
};

// The corner after `corner` in its face (corners 3f, 3f + 1, 3f + 2 of face f); a corner's side
// runs from its point to the next corner's.
template <typename Index>
constexpr Index next_corner(Index corner) {
  return corner % 3 == 2 ? corner - 2 : corner + 1;  // one remainder: preparation calls this ~7 times a corner
}

// `mesh` must have passed the size, finite and index-range checks. Deterministic.
PreparedMesh prepare_mesh(const AnimatedMeshView& mesh, const WeldInput& input);

}  // namespace animlod::detail
