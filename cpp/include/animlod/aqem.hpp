// AQEM: simplification of a deforming mesh over all its frames by edge collapse, with the
// animated quadric error metric and motion-feature weights of Yang et al. 2019 (Eqs. 1-7).
//
// Every collapse is shared by all frames (one connectivity), and the new vertex gets its own
// optimal position in every frame. One run yields several levels of detail from the same
// collapse sequence, plus the ordered collapse record.
//
// Any indexed triangle mesh is accepted, as real assets come: vertices duplicated along UV,
// normal and material seams are welded into one surface and the seams are kept (a seam vertex
// only collapses along its seam); degenerate and repeated faces are dropped; non-manifold
// edges and vertices are cut into manifold pieces whose shared vertices are locked, so the
// pieces stay stitched. AqemResult::preparation counts what was done.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "animlod/animated_mesh_view.hpp"
#include "animlod/motion_features.hpp"
#include "animlod/status.hpp"

namespace animlod {

// Where the vertex of a collapse goes.
enum class Placement {
  // Eq. 5 in every frame: v_f = X_f^-1 Y_f (the paper). Smallest error; the new vertex may
  // stand for a different point of the surface in different frames.
  optimal,
  // One point of the collapsed edge for all frames, kept + t (removed - kept) with the t that
  // minimises the summed quadric: the vertex keeps one identity, so interpolated UVs and
  // merged skin weights stay consistent with its positions (used for skinned meshes).
  on_edge,
};

// What simplify_animated builds and how: the levels, the weights of Eq. 6, the quadrics, the
// inversion test and where collapsed vertices go.
struct AqemOptions {
  // Levels as fractions of the face count M' left after dropping degenerate and repeated faces,
  // each in (0, 1]. Ignored when target_face_counts is not empty. A level that no legal collapse
  // can reach stops at the smallest mesh reachable, with reached = false.
  std::vector<double> target_ratios = {0.5};
  // Levels as face counts, each in [1, M].
  std::vector<size_t> target_face_counts;
  // Asset units. The run stops before a collapse whose error (an RMS plane distance, see
  // CollapseRecord::error) exceeds it; levels not reached then hold the last mesh and
  // reached = false.
  double max_error = std::numeric_limits<double>::infinity();
  // Weights of Eq. 6 from the motion features; off gives every vertex weight 1.
  bool use_motion_features = true;
  // How motion features are found and weighted when use_motion_features is on.
  MotionFeatureOptions motion_features;
  // Adds, per frame, a plane through every boundary edge and every attribute-seam edge
  // perpendicular to its face, so that open borders and seams keep their shape (Garland and
  // Heckbert 1997, section 6.1).
  bool boundary_quadrics = true;
  // Adds, per frame, the squared distance from its position (once per plane of the point) to
  // the quadric of every needle tip, a point whose edges all leave within 45 degrees of their
  // mean direction in every frame of the quadrics (the end of a leg, a beak, a spike). A spike's faces lie nearly parallel to
  // it, so plane quadrics charge moving its tip onto its base only a small part of the distance
  // it moves, and quadric simplification removes spikes first; with this, a tip's error is its
  // displacement. Off: the paper's quadrics. Meshes without tips simplify bit for bit alike.
  bool tip_quadrics = true;
  // Rejects collapses that invert a face according to Eq. 7, summed over every frame F (also
  // the frames outside frames_used, at their on-edge positions). The sum lets a face flip in a
  // few frames when it gains area in the others.
  bool check_inversion = true;
  // Beside Eq. 7's sum, rejects a collapse that folds a face deeply in any single frame: the
  // moved corner passes the line of the face's opposite edge, within the face's plane in that
  // frame, by more than fold_limit times that edge's length. On a clean box limb whose flat
  // sides bend in their plane, the sum lets triangles fold across the knee in the few bent
  // frames (synth.kicking_box_leg at 50%: 15% of the diagonal, 0.5% with the default 1). A
  // limit of 0 (no flip in any frame) ruins noisy captures, whose noise flips some face in some
  // frame near most collapses (Xbot's baked clip with noise at 25%: 0.26% -> 5.7%), less deeply
  // than an edge (bench_aqem's quality and baked tables). Shallow folds of clean meshes pass the
  // default too (a Blender export's box limbs: 1.65% at 50%, 0.15% with 0). Infinity: Eq. 7
  // alone, the paper's test. Ignored when check_inversion is false.
  double fold_limit = 1.0;
  // Quadrics over K frames only: 0 uses every frame, otherwise K frames chosen by
  // farthest-point sampling of the poses (see frames_used). Only the quadrics shrink to
  // O(V K) memory and placement time; positions, the inversion test and the outputs stay
  // O(V F), every frame being kept (frames outside the K placed on the collapsed edge).
  // Motion features always look at every frame (they cost O(E F) time and O(E) memory).
  size_t max_frames = 0;
  // Explicit frames for the quadrics; overrides max_frames when not empty.
  std::vector<int32_t> frame_subset;
  // With max_frames 0 and no frame_subset: quadrics over every frame unless they would take
  // more than this many bytes (80 per welded point and frame: 16 GB for a 1,200-frame capture
  // of 166k points, which failed to allocate); then over the most frames that fit, chosen as
  // max_frames chooses them (frames_used says which). 0: no limit.
  size_t quadric_memory_limit = size_t{2} << 30;
  // Called now and then with (collapses done, collapses needed for the last level).
  std::function<void(size_t, size_t)> progress;
  // Where the vertex of a collapse goes (see Placement).
  Placement placement = Placement::optimal;
  // Welds vertices that are equal in every frame, in position_attributes and in skin, so that
  // seam copies form one surface. Off: every input vertex is its own point (seams are borders).
  bool weld = true;
  // Fills CollapseRecord::positions, the merged vertex in every frame (12 bytes per collapse
  // and frame: 2 GB for a 1,200-frame capture's 150k collapses). Off: they stay empty; the
  // levels and the rest of the record are the same.
  bool record_positions = true;
};

// Optional per-vertex and per-face inputs; a null pointer means "not given". attributes must be
// given when attribute_count > 0 (likewise position_attributes), and skin_joints and
// skin_weights together (simplify_animated checks).
//
// attributes may differ between copies of a position (UV, normal, colour): where they do, the
// copies form a seam. position_attributes follow the position (morph target deltas): copies
// weld only when they agree, and a collapse blends them once per position. Skin weights also
// follow the position.
struct AqemVertexData {
  const uint8_t* locked = nullptr;        // (V,) nonzero: the vertex keeps its positions and is
                                          //      never removed (edges may collapse into it)
  const float* importance = nullptr;      // (V,) > 0, multiplies the vertex weight of Eq. 6
  const float* attributes = nullptr;      // (V, A) interpolated along collapsed edges (e.g. UVs)
  size_t attribute_count = 0;             // A
  const int32_t* skin_joints = nullptr;   // (V, K) joint per influence
  const float* skin_weights = nullptr;    // (V, K) influence weights; merged, top K kept
  size_t influence_count = 0;             // K
  const float* position_attributes = nullptr;  // (V, B) blended along collapsed edges per position
  size_t position_attribute_count = 0;         // B
  const int32_t* face_groups = nullptr;   // (M,) material or primitive of each face: copies of a
                                          //      position in different groups never merge, so
                                          //      group borders are seams
  const uint8_t* guarded = nullptr;       // (V,) nonzero: the vertex stays in place (like locked)
                                          //      until no other collapse is legal, then it is free
                                          //      (sharp corners kept while the targets allow)
};

struct AqemLevel {
  size_t target_face_count = 0;      // with the mirrors of its faces (AqemPreparation::mirrored_faces)
  bool reached = false;              // false when max_error or legality stopped the run first
  bool stopped_by_max_error = false; // not reached because the next collapse's error exceeds max_error
                                     // (false: no legal collapse was left)
  size_t collapse_count = 0;         // the level is the first collapse_count records applied
  double error = 0.0;                // asset units: the largest collapse error so far (see
                                     // CollapseRecord::error)
  std::vector<int32_t> faces;        // (M', 3) indices into the kept vertices, corners in input order;
                                     // the mirrors of two-sided faces last, on the same vertices
  std::vector<int32_t> face_sources; // (M',) input face each face comes from (its primitive)
  std::vector<int32_t> kept_vertices;  // (V',) original index of each kept vertex, ascending
  std::vector<int32_t> vertex_map;   // (V,) original vertex -> index of the kept vertex it merged
                                     //      into; -1 for vertices no face references, vertices of
                                     //      dropped faces only, and vertices of a piece that
                                     //      collapsed away entirely (a lone triangle)
  std::vector<float> positions;      // (F, V', 3) positions of the kept vertices in every frame
  std::vector<float> attributes;     // (V', A)
  std::vector<int32_t> skin_joints;  // (V', K)
  std::vector<float> skin_weights;   // (V', K) rows of vertices made by a collapse: sorted by
                                     // decreasing weight, summing to 1, zero-padded; the
                                     // others: the input's rows unchanged
  std::vector<float> position_attributes;  // (V', B)
};

// What simplify_animated did to the input before simplifying (see the top of this header).
struct AqemPreparation {
  size_t degenerate_faces = 0;       // dropped: two corners at one welded position
  size_t duplicate_faces = 0;        // dropped: the same corners as an earlier face, same turn
  size_t mirrored_faces = 0;         // the same corners as an earlier face in the reverse turn (a
                                     // two-sided sheet): simplified with it, and written on every
                                     // level as its reverse, on the same vertices
  size_t welded_vertices = 0;        // vertices welded onto a lower-numbered copy
  size_t seam_vertices = 0;          // welded positions whose copies keep different attributes
  size_t split_vertices = 0;         // copies made to cut non-manifold edges and vertices (locked)
  size_t unreferenced_vertices = 0;  // vertices no face uses (not in any level)
  size_t face_count = 0;             // M', the faces simplified
};

// The ordered collapses (structure of arrays, C collapses): vertex removed[i] merged into
// vertex kept[i], which moved to positions[i]. Vertex indices are the input's.
struct CollapseRecord {
  std::vector<int32_t> removed;   // (C,) the lowest input vertex at the removed position
  std::vector<int32_t> kept;      // (C,) the lowest input vertex at the kept position
  std::vector<float> positions;   // (C, F, 3) new positions of the kept vertex in every frame;
                                  //      empty when AqemOptions::record_positions is off
  std::vector<double> cost;       // (C,) weighted cost of Eq. 6
  std::vector<double> error;      // (C,) asset units: RMS distance of the new vertex to the planes
                                  //      of its merged quadric, over those planes and the frames
                                  //      used: sqrt(sum_k Q_k(v_k) / (K planes)), Eqs. 3-6 unweighted
};

// Wall-clock seconds of one call's phases: where its time goes (bench/bench_aqem.py prints them).
struct AqemTimings {
  double preparation = 0.0;      // checks, weld, dropped faces, cuts (before any collapse)
  double motion_features = 0.0;  // Eq. 6's features (0 when off)
  double connectivity = 0.0;     // the engine's OpenMesh connectivity and per-point state (the
                                 // faces' quadrics are summed meanwhile, on another thread)
  double quadrics = 0.0;         // what the quadrics take beyond that: the rest of the faces',
                                 // the border and seam sides'
  double ranking = 0.0;          // costs of every collapsible edge (each pass's, or the greedy heap's first)
  double choosing = 0.0;         // collapse passes: ordering candidates by cost and choosing a pass's
  double collapsing = 0.0;       // collapse attempts (the greedy order: its re-keying too)
  double levels = 0.0;           // the levels' meshes and arrays
};

struct AqemResult {
  std::vector<AqemLevel> levels;     // one per target, finest first
  CollapseRecord collapses;
  std::vector<int32_t> frames_used;  // frames whose quadrics drove the simplification
  std::vector<float> vertex_weights; // (V,) weights of Eq. 6 (motion features x importance),
                                     //      1 for vertices no face uses
  AqemPreparation preparation;
  AqemTimings seconds;
};

// The checks of `options` that need no mesh, run first by simplify_animated: no level, a target
// ratio outside (0, 1], a face count of 0, a negative or NaN max_error, a negative frame in
// frame_subset, and the motion-feature options' (check_motion_feature_options) when
// use_motion_features is on. A caller that takes options long before it has the mesh (a batch
// manifest) can refuse them up front.
Status check_aqem_options(const AqemOptions& options);

// Simplifies `mesh` to every target of `options`.
//
// Placement (Eq. 5, Placement::optimal): per frame, v = X^-1 Y of the merged quadric; where a
// frame's X is singular, or v lies farther from the edge's midpoint than the edge is long, the
// best of the two endpoints and the midpoint (one choice shared by those frames).
// Placement::on_edge puts the vertex at one point of the edge. In frames outside frames_used the
// new vertex sits on the collapsed edge at the parameter that best matches the optimal
// positions of the used frames. Attributes and skin weights are interpolated with that same
// parameter. Ties in cost are broken by edge index, so the output is deterministic.
//
// Errors (the message names the element): no frames or faces, sizes beyond int32 indices, a
// non-finite position, a face index outside [0, V); a target ratio outside (0, 1] or face count
// outside [1, M]; a frame index outside [0, F); a non-positive or non-finite importance; a skin
// joint index below 0; a negative or non-finite skin weight; a non-finite attribute; a count > 0
// with null data; only one of skin_joints and skin_weights. On error (or an exception thrown by
// options.progress) `out` is left empty.
Status simplify_animated(const AnimatedMeshView& mesh, const AqemVertexData& vertex_data,
                         const AqemOptions& options, AqemResult& out);

}  // namespace animlod
