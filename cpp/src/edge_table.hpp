// The undirected edges of a triangle mesh with the faces on each side, built by sorting the
// 3M face sides (no halfedge structure needed for validation and dihedral angles).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace animlod::detail {

struct EdgeTable {
  // Sorted by (lower, higher) vertex index.
  std::vector<std::array<int32_t, 2>> vertices;
  // faces[e][0]: the face that traverses edge e from lower to higher vertex; faces[e][1]: the
  // face that traverses it from higher to lower; -1 where there is none (boundary).
  std::vector<std::array<int32_t, 2>> faces;
  // Set when a face side could not be stored: three or more faces on one edge, or two faces
  // traversing it in the same direction. Holds the edge and the faces involved.
  bool manifold = true;
  std::array<int32_t, 2> bad_edge{-1, -1};
  std::array<int32_t, 3> bad_faces{-1, -1, -1};

  size_t size() const { return vertices.size(); }
  bool is_boundary(size_t e) const { return faces[e][0] < 0 || faces[e][1] < 0; }
};

// faces (M, 3) with indices already known to be in range and distinct within each face.
EdgeTable build_edge_table(const int32_t* faces, size_t face_count);

}  // namespace animlod::detail
