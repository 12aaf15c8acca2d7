// The TDAG's vertex hierarchy from a collapse order (Shamir and Pascucci 2001, Sections 2 and
// 4): the collapse nodes shared by every frame, and for one frame's order the dependencies that
// make every cut valid. Pure bookkeeping over the faces; the collapses themselves are chosen by
// the collapse engine (tdag_policy.hpp) or taken from AQEM's record.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "animlod/status.hpp"
#include "quadric.hpp"

namespace animlod::detail {

// The collapse nodes of a TDAG build, shared by all frames: a collapse is identified by its
// two child nodes, the one whose position it keeps first, so frames that merge the same two
// vertex clusters the same way share one node. Nodes 0 .. V-1 are vertices; collapse c is
// node V + c.
class CollapseTable {
 public:
  explicit CollapseTable(int32_t vertex_count) : vertex_count_(vertex_count) {
    representative.resize(static_cast<size_t>(vertex_count));
    for (int32_t v = 0; v < vertex_count; ++v) representative[static_cast<size_t>(v)] = v;
  }

  // The node merging `removed` into `kept` (kept's position), or -1.
  int32_t find(int32_t kept, int32_t removed) const {
    auto it = index_.find(key(kept, removed));
    return it == index_.end() ? -1 : it->second;
  }
  // The node merging `removed` into `kept`, created when new (its killed faces unknown, -1).
  int32_t add(int32_t kept, int32_t removed) {
    auto [it, inserted] = index_.try_emplace(key(kept, removed), static_cast<int32_t>(representative.size()));
    if (inserted) {
      kept_child.push_back(kept);
      removed_child.push_back(removed);
      killed.push_back({-1, -1});
      representative.push_back(representative[static_cast<size_t>(kept)]);
    }
    return it->second;
  }
  int32_t vertex_count() const { return vertex_count_; }
  size_t collapse_count() const { return kept_child.size(); }

  std::vector<int32_t> kept_child;             // (C,) the child whose position the node takes
  std::vector<int32_t> removed_child;          // (C,)
  std::vector<std::array<int32_t, 2>> killed;  // (C,) faces the collapse removes, -1 padded
  std::vector<int32_t> representative;         // (V + C,)

 private:
  static uint64_t key(int32_t kept, int32_t removed) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(kept)) << 32) | static_cast<uint32_t>(removed);
  }
  int32_t vertex_count_;
  std::unordered_map<uint64_t, int32_t> index_;
};

// One frame's hierarchy: its collapses in the order applied and what each one depends on.
struct FrameHierarchy {
  std::vector<int32_t> nodes;        // collapse node ids, in order
  std::vector<int32_t> dep_offsets;  // (nodes.size() + 1,)
  std::vector<int32_t> dep_nodes;    // collapse node ids, each earlier in `nodes`
};

// One collapse of a frame's order: vertex `removed` merges into vertex `kept` (the surviving
// vertex of the connectivity); the new node takes `removed`'s position when from_removed.
struct VertexCollapse {
  int32_t removed = -1;
  int32_t kept = -1;
  bool from_removed = false;
};

// Applies `collapses` in order to the faces (M, 3) over `vertex_count` vertices, adding their
// nodes to `table` and filling `out`. The dependencies of a collapse are the collapses that last
// changed a face around either endpoint: a set of collapses closed under them, applied in order
// to the input, meets at every collapse the same faces around its edge as the full order did,
// so every such set (a cut of the DAG) is a valid manifold mesh; and the faces a collapse
// removes are those with one corner in each child's cluster, whatever else is applied.
//
// `twins` (may be null): for a vertex, other vertices standing for the same input vertex (the
// copies of a non-manifold vertex cut apart); a collapse whose kept vertex does not share a face
// with the removed one uses the twin that does. Errors (naming the collapse): an index out of
// range, an endpoint already removed, endpoints that share no face.
Status record_hierarchy(const int32_t* faces, size_t face_count, size_t vertex_count,
                        const std::vector<VertexCollapse>& collapses,
                        const std::vector<std::vector<int32_t>>* twins, CollapseTable& table, FrameHierarchy& out);

// A boundary edge a -> b of the face (a, b, c).
struct BoundarySide {
  int32_t a, b, c;
};
// The boundary edges of a manifold mesh.
std::vector<BoundarySide> boundary_sides(const int32_t* faces, size_t face_count);
// Per-vertex quadrics (V,) of one frame: face planes and, when `boundary` is not null, the
// planes through its boundary edges perpendicular to their faces (Garland and Heckbert 1997).
void vertex_quadrics(const float* positions, const int32_t* faces, size_t vertex_count, size_t face_count,
                     const std::vector<BoundarySide>* boundary, std::vector<Quadric>& out);

}  // namespace animlod::detail
