// The TDAG's collapse loop: quadric half-edge decimation of one frame with a pluggable
// priority (the online construction's history term, Section 2 / [17]), recording the vertex
// hierarchy and the dependencies that make every cut valid.
//
// This loop is deliberately isolated from the rest of the TDAG: it is the part to move onto
// the shared collapse engine (cpp/src/collapse_engine.*) as a cost-and-placement policy
// (half-edge placement, quadric cost, CollapsePriority as the priority) with the TDAG's
// pre/post-collapse hooks (dependency and node bookkeeping).
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
// two child nodes, so frames that merge the same two vertex clusters share one node. Nodes
// 0 .. V-1 are input vertices; collapse c is node V + c.
class CollapseTable {
 public:
  explicit CollapseTable(int32_t vertex_count) : vertex_count_(vertex_count) {
    representative.resize(static_cast<size_t>(vertex_count));
    for (int32_t v = 0; v < vertex_count; ++v) representative[static_cast<size_t>(v)] = v;
  }

  // The node merging `removed` into `kept`, or -1.
  int32_t find(int32_t kept, int32_t removed) const {
    auto it = index_.find(key(kept, removed));
    return it == index_.end() ? -1 : it->second;
  }
  // The node merging `removed` into `kept`, created with its killed faces when new.
  int32_t add(int32_t kept, int32_t removed, std::array<int32_t, 2> killed_faces) {
    auto [it, inserted] = index_.try_emplace(key(kept, removed), static_cast<int32_t>(representative.size()));
    if (inserted) {
      kept_child.push_back(kept);
      removed_child.push_back(removed);
      killed.push_back(killed_faces);
      representative.push_back(representative[static_cast<size_t>(kept)]);
    }
    return it->second;
  }
  int32_t vertex_count() const { return vertex_count_; }
  size_t collapse_count() const { return kept_child.size(); }

  std::vector<int32_t> kept_child;             // (C,)
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
  std::vector<double> costs;         // quadric cost of each, in the decimated frame
  std::vector<int32_t> dep_offsets;  // (nodes.size() + 1,)
  std::vector<int32_t> dep_nodes;    // collapse node ids, each earlier in `nodes`
};

// The priority of a half-edge collapse in the decimation loop (lower first).
class CollapsePriority {
 public:
  virtual ~CollapsePriority() = default;
  // kept_node, removed_node: the hierarchy nodes of the two endpoints now; cost: the collapse's
  // quadric cost in the decimated frame.
  virtual double priority(int32_t kept_node, int32_t removed_node, double cost) const = 0;
};

struct DecimationInput {
  const float* positions = nullptr;  // (V, 3) the geometry whose quadrics order the collapses
  const int32_t* faces = nullptr;    // (M, 3) validated: manifold, consistently oriented
  size_t vertex_count = 0;
  size_t face_count = 0;
  bool boundary_quadrics = true;
  bool check_inversion = true;                  // in `positions`
  const CollapsePriority* priority = nullptr;   // null: the cost itself
  // Replay: apply these collapses (input vertex indices) in order instead of choosing; each
  // must be legal on the connectivity reached (no inversion test).
  const int32_t* replay_removed = nullptr;
  const int32_t* replay_kept = nullptr;
  size_t replay_count = 0;
};

// Decimates until no legal collapse is left (or replays), adding the collapses to `table` and
// the frame's order to `out`. Errors: a face OpenMesh cannot add; a replayed collapse whose
// edge is missing or illegal (named by its index).
Status decimate_frame(const DecimationInput& input, CollapseTable& table, FrameHierarchy& out);

// A boundary edge a -> b of the face (a, b, c).
struct BoundarySide {
  int32_t a, b, c;
};
// The boundary edges of a validated mesh.
std::vector<BoundarySide> boundary_sides(const int32_t* faces, size_t face_count);
// Per-vertex quadrics (V,) of one frame: face planes (Eqs. 1-3 of the QEM) and, when
// `boundary` is not null, the perpendicular planes of its boundary edges.
void vertex_quadrics(const float* positions, const int32_t* faces, size_t vertex_count, size_t face_count,
                     const std::vector<BoundarySide>* boundary, std::vector<Quadric>& out);

}  // namespace animlod::detail
