// The TDAG's stored fields (what a .tdag file holds) and the links derived from them when a
// TDAG is built or loaded. Private to the core; animlod/tdag.hpp is the public face.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "animlod/tdag.hpp"
#include "animlod/tdag_time_tag.hpp"
#include "tdag_error_codes.hpp"

namespace animlod::detail {

struct TdagData {
  // ---- stored ----
  int32_t frame_count = 0;   // F
  int32_t vertex_count = 0;  // V: nodes 0..V-1 are the input vertices (leaves)
  std::vector<int32_t> faces;  // (M, 3) over the TDAG's vertices
  // (M,) 1 for a face also drawn turned over: the input held it twice, once in each turn (a
  // two-sided sheet), and the TDAG simplifies one side and hands out both. Empty: none.
  std::vector<uint8_t> two_sided;
  std::vector<int32_t> input_points;  // (input V,) TDAG vertex of each input vertex, -1: unused
  AffineBase affine_base = AffineBase::first;
  Governing governing = Governing::first;
  int32_t governing_frame = 0;
  double history_weight = 0.0;
  double scale = 1.0;             // error code scale: bounding-box diagonal of frame 0
  std::vector<double> maps;       // (F, 3, 4) affine maps A_t
  std::vector<float> residuals;   // (F, V, 3) residual meshes A_t^-1 P_t
  // Collapse c (node V + c): removed_child merged into kept_child.
  std::vector<int32_t> kept_child;            // (C,)
  std::vector<int32_t> removed_child;         // (C,)
  std::vector<std::array<int32_t, 2>> killed; // (C,) faces the collapse removes (-1: none)
  std::vector<TimeTag> alive;                 // (C,) frames in whose hierarchy the collapse is
  // Dependencies (multiple-valued, tagged): collapse c needs the collapses
  // dep_nodes[dep_offsets[c] .. dep_offsets[c + 1]) (node ids) on the frames of dep_tags.
  std::vector<int32_t> dep_offsets;  // (C + 1,)
  std::vector<int32_t> dep_nodes;
  std::vector<TimeTag> dep_tags;
  // Error bounds (single-valued, tagged): (F, C) the code of every collapse in every frame,
  // kNoCode where it has none (not alive). Stored as runs per collapse (tdag_error_codes.hpp).
  std::vector<uint16_t> codes_by_frame;

  // ---- derived (build and load) ----
  std::vector<int32_t> representative;     // (V + C,) the leaf whose position a node takes
  std::vector<int32_t> parent_offsets;     // (V + C + 1,) collapses that have the node as a child
  std::vector<int32_t> parent_nodes;
  std::vector<int32_t> dependent_offsets;  // (C + 1,) reverse dependency links
  std::vector<int32_t> dependent_nodes;
  std::vector<int32_t> dependent_links;    // index into dep_nodes / dep_tags of the same link
  std::vector<int32_t> change_offsets;     // (F + 1,) collapses whose structure or error changes at t
  std::vector<int32_t> change_nodes;
  std::vector<int32_t> event_offsets;      // (F + 1,) collapses whose structure (alive, links) changes at t
  std::vector<int32_t> event_nodes;
  bool static_structure = true;            // every collapse and link alive on every frame
  // With a static structure: the position of every leaf in a depth-first order of the forest
  // (V,) and every node's range of positions [begin, end) (V + C, 2), so that "is vertex v
  // under node n" is O(1). Empty otherwise.
  std::vector<int32_t> leaf_position;
  std::vector<std::array<int32_t, 2>> leaf_range;

  size_t collapse_count() const { return kept_child.size(); }
  size_t node_count() const { return static_cast<size_t>(vertex_count) + collapse_count(); }
  size_t face_count() const { return faces.size() / 3; }

  bool collapse_alive(size_t c, int32_t frame) const { return static_structure || alive[c].alive_at(frame); }
  bool link_alive(size_t link, int32_t frame) const { return static_structure || dep_tags[link].alive_at(frame); }

  // The error code of collapse c at `frame`; kNoCode (never collapsed) where it is not alive.
  uint16_t error_code(size_t c, int32_t frame) const {
    return codes_by_frame[static_cast<size_t>(frame) * collapse_count() + c];
  }

  // The collapse node that has `node` as a child at `frame`, or -1 (a root at that frame).
  int32_t parent_at(int32_t node, int32_t frame) const {
    for (int32_t i = parent_offsets[node]; i < parent_offsets[node + 1]; ++i) {
      const int32_t parent = parent_nodes[i];
      if (collapse_alive(static_cast<size_t>(parent - vertex_count), frame)) return parent;
    }
    return -1;
  }
};

// Fills the derived fields from the stored ones. Returns an error naming the element when the
// stored fields are inconsistent (a child id not below its parent, a node merged twice in one
// frame, an index out of range), which a corrupted or hand-made file can produce.
Status derive_links(TdagData& data);

}  // namespace animlod::detail
