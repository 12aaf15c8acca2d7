// The edge-collapse engine shared by every simplifier of the core (AQEM, the TDAG, region
// weighted faces). In the spirit of libigl's decimate(cost_and_placement, stopping_condition,
// pre_collapse, post_collapse): the engine owns the connectivity, the heap, legality and the
// bookkeeping of points, wedges and levels; a CollapsePolicy says what an edge costs, where the
// merged point goes and what the policy merges on a collapse.
//
// Points are welded positions (see mesh_preparation.hpp); wedges are the input vertices that
// stand for a point in the faces around it. A collapse moves every wedge of the removed point
// to the wedge of the kept point on the same side of the collapsed edge, so attribute seams
// only collapse along themselves (meshoptimizer's rule) and never open.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <OpenMesh/Core/Mesh/TriConnectivity.hh>

#include "animlod/animated_mesh_view.hpp"
#include "indexed_heap.hpp"
#include "mesh_preparation.hpp"

namespace animlod::detail {

// An edge collapse being considered: point `removed` merges into point `kept`.
struct Candidate {
  int32_t kept = -1;
  int32_t removed = -1;
  double cost = 0.0;   // heap key
  double error = 0.0;  // asset units; compared with max_error and reported per level
  double t = 0.0;      // attributes and skin weights blend as kept + t (removed - kept)
};

// An edge that can collapse, with its cost: what collapse passes rank and the greedy order's
// heap starts from.
struct RankedEdge {
  double cost, error;  // Candidate's
  int32_t edge, kept, removed;
};

class CollapsePolicy {
 public:
  virtual ~CollapsePolicy() = default;
  // Fills cost and error of `candidate` (kept and removed are set). Called to key every edge,
  // so it leaves out what only a collapse needs: the placement.
  virtual void evaluate(Candidate& candidate) = 0;
  // Writes the merged point's position in every frame F into `placed` and sets t where
  // evaluate() did not; called right after evaluate() of the same candidate, only for a collapse
  // about to be tried.
  virtual void place(Candidate& candidate, std::vector<Eigen::Vector3d>& placed) = 0;
  // The engine is applying `candidate`: merge the policy's per-point state into `kept`.
  virtual void merge(const Candidate& candidate) = 0;
  // Collapse passes evaluate every edge at once on up to concurrency() threads: worker w in
  // [0, concurrency()) calls evaluate_concurrently, which fills cost and error like evaluate()
  // and must not write state another worker reads (no merge() runs meanwhile).
  // With two or more, they also perform collapses on workers 0 and 1 at once, in parts of the
  // mesh that share no point: then evaluate_concurrently, place_concurrently (the placement of
  // the worker's last evaluation) and merge run concurrently, and may only read and write the
  // state of the candidate's two points and the worker's own scratch. Worker 0 is the engine's
  // own thread, whose evaluations are those of evaluate() and place().
  virtual size_t concurrency() const { return 1; }
  virtual void evaluate_concurrently(Candidate& candidate, size_t /*worker*/) { evaluate(candidate); }
  virtual void place_concurrently(Candidate& candidate, std::vector<Eigen::Vector3d>& placed, size_t /*worker*/) {
    place(candidate, placed);
  }
};

// Per-vertex data the engine carries through collapses (all optional).
struct CarriedData {
  const uint8_t* locked = nullptr;              // (V,) input vertices that never move
  const uint8_t* guarded = nullptr;             // (V,) input vertices that stay in place while any
                                                //      other collapse is legal
  const float* attributes = nullptr;            // (V, A) per wedge, interpolated with t
  size_t attribute_count = 0;
  const float* position_attributes = nullptr;   // (V, B) per point, interpolated with t
  size_t position_attribute_count = 0;
  const int32_t* skin_joints = nullptr;         // (V, K) per point, merged with t
  const float* skin_weights = nullptr;
  size_t influence_count = 0;
};

struct EngineOptions {
  bool check_inversion = true;  // Eq. 7 summed over every frame
  // Also reject a fold deeper than this many opposite-edge lengths in any one frame (AqemOptions).
  double fold_limit = std::numeric_limits<double>::infinity();
  double max_error = std::numeric_limits<double>::infinity();
  std::function<void(size_t, size_t)> progress;
  // false: one global greedy order (an indexed heap, re-keyed after every collapse). true:
  // meshoptimizer's collapse passes: every edge is evaluated (on several threads) and ranked by
  // cost; a pass chooses collapses in that order while neither endpoint is taken in the pass
  // and the cost stays within pass_cost_growth times the cost of the pass's goal-th candidate,
  // then performs them in edge order (see run_passes).
  bool collapse_passes = false;
  double pass_cost_growth = 1.5;
  // Collapse passes hand over to the greedy order once this few edges can collapse; meshes
  // with no more than passes_above_edges edges use the greedy order throughout (they take well
  // under a second, and their Hausdorff errors at coarse levels move by tens of percent with the
  // order: see README's AQEM speed section).
  size_t greedy_tail_edges = 4096;
  size_t passes_above_edges = 100000;
  // Collapse passes rank again from their last ranking, evaluating only the candidates at
  // points a collapse changed; false evaluates every edge at every pass (the same result,
  // slower: the reference the reuse is tested against).
  bool rank_from_last = true;
  // Fills EngineRecord::positions (C F 3 floats), which only AQEM's public record gives out.
  bool record_positions = false;
};

// One level: the surviving faces over the surviving wedges (input vertex indices).
struct EngineLevel {
  size_t target_face_count = 0;
  bool reached = false;
  bool stopped_by_max_error = false;    // not reached because the next collapse's error exceeds max_error
  size_t collapse_count = 0;
  double error = 0.0;                   // largest collapse error so far
  std::vector<int32_t> faces;           // (M', 3) output vertex indices
  std::vector<int32_t> face_sources;    // (M',) input face of each output face
  std::vector<int32_t> kept_vertices;   // (V',) input vertex of each output vertex, ascending
  std::vector<int32_t> vertex_map;      // (V,) input vertex -> output vertex, -1 when dropped
  std::vector<float> positions;         // (F, V', 3)
  std::vector<float> attributes;        // (V', A)
  std::vector<float> position_attributes;  // (V', B)
  std::vector<int32_t> skin_joints;     // (V', K)
  std::vector<float> skin_weights;      // (V', K)
};

// Wall-clock seconds of run()'s parts; collapsing is the rest of run().
struct EngineTimings {
  double ranking = 0.0, choosing = 0.0, collapsing = 0.0, levels = 0.0;
};

struct EngineRecord {
  std::vector<int32_t> removed, kept;  // (C,) input vertex standing for each point
  std::vector<float> positions;        // (C, F, 3) with EngineOptions::record_positions, else empty
  std::vector<double> cost, error;     // (C,)
};

class CollapseEngine {
 public:
  // `mesh` gives the frames of the input vertices; `prepared` its points, faces and wedges.
  CollapseEngine(const AnimatedMeshView& mesh, const PreparedMesh& prepared, const CarriedData& data,
                 const EngineOptions& options);

  size_t frame_count() const { return frame_count_; }
  size_t point_count() const { return point_count_; }
  Eigen::Vector3d position(int32_t point, size_t frame) const {
    const float* p = &positions_[(static_cast<size_t>(point) * frame_count_ + frame) * 3];
    return {p[0], p[1], p[2]};
  }
  bool locked(int32_t point) const { return locked_[point] == kLocked || (locked_[point] == kGuarded && !released_); }
  // Sides (a, b, c) whose edge a-b must keep its shape, with c the third point of the face on
  // the other side: every boundary halfedge (in OpenMesh's halfedge order), then both sides of
  // every attribute-seam edge.
  const std::vector<std::array<int32_t, 3>>& border_sides() const { return border_sides_; }
  const std::vector<std::array<int32_t, 3>>& seam_sides() const { return seam_sides_; }

  // Collapses until every target face count (descending) is reached or nothing legal remains.
  void run(CollapsePolicy& policy, const std::vector<size_t>& targets, std::vector<EngineLevel>& levels,
           EngineRecord& record);
  const EngineTimings& timings() const { return timings_; }

 private:
  using TriMesh = OpenMesh::TriConnectivity;

  void run_collapses(CollapsePolicy& policy, const std::vector<size_t>& targets, std::vector<EngineLevel>& levels,
                     EngineRecord& record);
  void build_connectivity();
  void link_paired_sides();
  void find_border_and_seam_sides();
  Candidate candidate_for(int32_t edge) const;
  Candidate evaluate(CollapsePolicy& policy, int32_t edge) const;
  int32_t corner_wedge(TriMesh::FaceHandle face, int32_t point) const;
  // What one collapse at a time needs, per worker (a cache line of its own: both workers write
  // theirs at every collapse).
  struct alignas(64) Workspace {
    std::vector<Eigen::Vector3d> placed;                    // (F,) the candidate's position in every frame
    std::vector<std::pair<int32_t, int32_t>> wedge_moves;  // removed wedge -> kept wedge
  };
  bool map_wedges(const Candidate& candidate, TriMesh::HalfedgeHandle collapse, Workspace& workspace) const;
  // Legality in two parts: the connectivity's (and the seams'), which needs no placement and is
  // tested first, and Eq. 7's, which tests the placement.
  bool is_legal_connectivity(const Candidate& candidate, TriMesh::HalfedgeHandle collapse, Workspace& workspace);
  bool keeps_orientation(const Candidate& candidate, const Workspace& workspace) const;
  int32_t collapse(CollapsePolicy& policy, const Candidate& candidate, TriMesh::HalfedgeHandle halfedge,
                   const Workspace& workspace, EngineRecord& record);
  enum class Attempt { collapsed, illegal, over_max_error };
  Attempt attempt_collapse(CollapsePolicy& policy, Candidate& candidate, int32_t edge, size_t worker,
                           EngineRecord& record, int32_t& faces_removed);
  Attempt try_collapse(CollapsePolicy& policy, Candidate candidate, int32_t edge, const std::vector<size_t>& targets,
                       std::vector<EngineLevel>& levels, EngineRecord& record);
  TriMesh::HalfedgeHandle removed_to_kept(const Candidate& candidate, int32_t edge) const;
  void run_greedy(CollapsePolicy& policy, const std::vector<RankedEdge>& ranked, const std::vector<size_t>& targets,
                  std::vector<EngineLevel>& levels, EngineRecord& record);
  void run_passes(CollapsePolicy& policy, const std::vector<size_t>& targets, std::vector<EngineLevel>& levels,
                  EngineRecord& record);
  struct Performed {
    size_t collapses = 0, illegal = 0;
  };
  Performed perform_in_halves(CollapsePolicy& policy, const std::vector<RankedEdge>& chosen,
                              const std::vector<size_t>& targets, std::vector<EngineLevel>& levels,
                              EngineRecord& record, std::vector<RankedEdge>& deferred);
  void split_points_in_halves(const std::vector<RankedEdge>& chosen);
  bool stays_in_half(const RankedEdge& entry, uint8_t half) const;
  void rank_collapsible_edges(CollapsePolicy& policy, std::vector<RankedEdge>& ranked);
  void rekey_around(CollapsePolicy& policy, TriMesh::VertexHandle vertex, bool all_edges);
  void park(int32_t edge);
  EngineLevel snapshot(size_t target, bool reached);

  const AnimatedMeshView& mesh_;
  const PreparedMesh& prepared_;
  const CarriedData& data_;
  const EngineOptions& options_;
  const size_t frame_count_;
  const size_t point_count_;
  std::vector<float> positions_;            // (P, F, 3) current positions, contiguous per point
  static constexpr uint8_t kLocked = 1, kGuarded = 2;
  bool release_guards(CollapsePolicy& policy);
  std::vector<uint8_t> locked_;             // (P,) 0, kLocked, or kGuarded (locked until released_)
  bool released_ = false;                   // set once nothing but guarded points could collapse
  bool in_passes_ = false;                  // run_passes is running (no heap to fill on release)
  std::vector<float> attributes_;           // (V, A) by wedge (input vertex)
  std::vector<float> position_attributes_;  // (P, B)
  std::vector<int32_t> skin_joints_;        // (P, K)
  std::vector<float> skin_weights_;         // (P, K)
  std::vector<int32_t> corner_points_;      // (M', 3) current point of every face corner
  std::vector<int32_t> corner_wedges_;      // (M', 3) current wedge of every face corner
  std::vector<int32_t> merged_into_;        // (P,) a point each removed point merged into
  std::vector<int32_t> wedge_merged_into_;  // (V,) a wedge each removed wedge merged into
  std::vector<int32_t> old_edges_;          // edges of the removed point before the current collapse
  std::vector<int32_t> valence_;            // (P,) points around each point (OpenMesh's valence, kept flat)
  std::vector<int32_t> point_wedge_;        // (P,) the wedge of every corner of the point, -1 when it may
                                            //      have several (a seam point)
  std::vector<uint8_t> parked_;             // (E,) popped while illegal; re-tried when the area changes
  std::vector<uint8_t> may_have_parked_;    // (P,) set when an edge of the point is parked
  std::array<Workspace, 2> workspaces_;     // per worker; the engine's own thread uses the first
  // Collapse passes rank again from their last ranking: a candidate's values depend only on
  // its two points (as the greedy order's re-keying around the kept point assumes too), and a
  // collapse deletes and re-points only edges at its two points, so an entry whose points no
  // collapse kept or removed since, and no guard release, is still live and costs the same.
  struct RankingCache {
    bool valid = false;            // `ranked` holds the last ranking of every collapsible edge
    std::vector<uint8_t> changed;  // (P,) kept or removed by a collapse since the last ranking
  };
  RankingCache ranking_cache_;              // empty outside collapse passes
  std::vector<uint8_t> half_;               // (P,) the half of the mesh each point is in (perform_in_halves)
  std::vector<std::array<int32_t, 3>> border_sides_, seam_sides_;
  TriMesh connectivity_;
  IndexedMinHeap heap_{0};
  size_t face_count_ = 0;
  double error_so_far_ = 0.0;
  bool stopped_by_max_error_ = false;  // the run ended at a collapse over max_error, not for want of one
  size_t collapse_count_ = 0;
  size_t next_level_ = 0;
  EngineTimings timings_;
  size_t planned_ = 0;
  void take_reached_levels(const std::vector<size_t>& targets, std::vector<EngineLevel>& levels);
};

}  // namespace animlod::detail
