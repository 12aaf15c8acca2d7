// TDAG: temporal and spatial level of detail for a deforming mesh (Shamir and Pascucci 2001,
// "Temporal and spatial level of details for dynamic meshes", Sections 2-5).
//
// One multi-resolution structure for all frames: a vertex hierarchy whose nodes are half-edge
// collapses (the merged vertex takes the position of one of its two children), whose
// fields carry time tags (tdag_time_tag.hpp): a collapse is alive on the frames whose
// hierarchy uses it, its dependencies (the collapses that must be applied before it, so that
// every cut is a valid mesh) and its error bound are tagged per frame. Positions are stored as
// residual meshes with one affine map per frame (tdag_affine.hpp). Queries return meshes for
// a (frame, tolerance) pair, fresh or updated incrementally in time or resolution, and the
// three temporal approximation levels of Section 5.
//
// Node ids: 0 .. V-1 are the input's vertices (leaves); V + c is the vertex made by collapse c.
// Error bounds are in asset units: a node's bound at frame t is at least the largest distance,
// at t, between an input vertex it stands for and the node's position, and is monotone up the
// hierarchy and along dependencies. A cut whose active nodes all have bound <= tolerance is a
// mesh within `tolerance` of the input frame in the two-sided Hausdorff distance (each input
// face maps linearly onto a face or edge of the cut).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "animlod/animated_mesh_view.hpp"
#include "animlod/status.hpp"
#include "animlod/tdag_affine.hpp"
#include "animlod/tdag_time_tag.hpp"

namespace animlod {

namespace detail {
struct TdagData;
struct CutState;
}  // namespace detail

// Which collapse order the hierarchy uses (Section 4).
enum class Governing {
  first,    // the quadric decimation of frame 0, shared by every frame
  average,  // ... of the average mesh
  frame,    // ... of frame TdagOptions::governing_frame ("an arbitrary mesh")
  aqem,     // the AQEM order over all frames (simplify_animated's collapse record)
  online,   // every frame decimated in turn, with a history term favouring the TDAG so far
};

// How build_temporal_dag orders, splits and checks the collapses of the TDAG.
struct TdagOptions {
  // The collapse order of the hierarchy (see Governing).
  Governing governing = Governing::first;
  // The frame that governs with Governing::frame, in [0, F).
  int32_t governing_frame = 0;
  // lambda >= 0 of the online construction: the priority of a collapse in frame t is its
  // quadric cost plus lambda * s * h, with s the mean collapse cost of frame t - 1 and h its
  // rank in frame t - 1's order divided by the collapse count (2 for a collapse frame t - 1
  // does not have). 0: every frame gets its own order; very large: frame 0's order everywhere.
  double history_weight = 1.0;
  // The base mesh of the affine split.
  AffineBase affine_base = AffineBase::first;
  // Planes perpendicular to open borders in the quadrics (Garland and Heckbert 1997).
  bool boundary_quadrics = true;
  // Rejects a collapse that flips a face of the decimated frame (the governing mesh; every
  // frame when online; Governing::aqem uses AQEM's Eq. 7 test over all frames).
  bool check_inversion = true;
  // Governing::aqem: weights of Eq. 6 from motion features.
  bool use_motion_features = true;
  // Called with (frames done, F) as the build goes. Exceptions propagate (nothing is built).
  std::function<void(size_t, size_t)> progress;
  // Welds vertices equal in every frame (UV-seam and flat-shading copies) into one vertex of
  // the TDAG, as AQEM does; off, every input vertex is its own. Either way degenerate and
  // repeated faces are dropped and non-manifold spots are cut apart (their copies are locked),
  // so the TDAG's vertices are "points" (TemporalDag::input_points maps the input onto them).
  bool weld = true;
};

// What the build measured. Costs are quadric costs (squared asset units) of the half-edge
// collapse, computed on the real frames (not the residuals), in each frame's own hierarchy.
struct TdagBuildReport {
  std::vector<int32_t> collapse_counts;  // (F,) collapses in each frame's hierarchy
  std::vector<double> max_cost;          // (C,) per collapse: max over its frames of its cost
  std::vector<int32_t> use_counts;       // (C,) frames in which the collapse is used (n_i)
  double seconds_affine = 0.0;           // affine split
  double seconds_hierarchy = 0.0;        // decimation (every frame when online)
  double seconds_fields = 0.0;           // costs, error bounds, time tags
};

class TdagFileSink;

// The TDAG: immutable once built or loaded; copies share the data.
class TemporalDag {
 public:
  TemporalDag();
  ~TemporalDag();
  TemporalDag(const TemporalDag&);
  TemporalDag& operator=(const TemporalDag&);

  bool empty() const;
  size_t frame_count() const;     // F
  size_t vertex_count() const;    // V: the TDAG's vertices (the welded points of the input)
  size_t face_count() const;      // M
  size_t collapse_count() const;  // C
  size_t node_count() const;      // V + C
  // (M, 3) faces over the TDAG's vertices (the input's, less degenerate and repeated ones, and
  // less the second side of two-sided faces).
  const int32_t* faces() const;
  // Whether face `face` is two-sided: the input also held it turned over (a sheet modelled with
  // a face per side). Cuts hand out its turned-over copy beside it.
  bool two_sided(size_t face) const;
  // Number of input vertices, and (input_vertex_count,) the TDAG vertex standing for each
  // (-1 for a vertex no face used).
  size_t input_vertex_count() const;
  const int32_t* input_points() const;
  Governing governing() const;
  AffineBase affine_base() const;
  // (3, 4) row-major affine map of `frame` (Section 3).
  const double* affine_map(int32_t frame) const;
  // (V, 3) residual mesh of `frame`.
  const float* residuals(int32_t frame) const;
  // (V, 3) the input frame, rebuilt as A_t applied to the residuals (float rounding only).
  void frame_positions(int32_t frame, float* out) const;

  // Collapse c in [0, C): the node it makes is V + c.
  int32_t kept_child(size_t c) const;
  int32_t removed_child(size_t c) const;
  // Frames on which collapse c is in the hierarchy.
  const TimeTag& alive(size_t c) const;
  // The input vertex whose position `node` takes.
  int32_t representative(int32_t node) const;
  // The collapse node having `node` as a child at `frame`, or -1.
  int32_t parent_at(int32_t node, int32_t frame) const;
  // Collapse nodes that collapse c needs at `frame`.
  std::vector<int32_t> dependencies_at(size_t c, int32_t frame) const;
  // Error bound of collapse c at `frame`, asset units; +infinity where c is not alive.
  double error_bound(size_t c, int32_t frame) const;
  // The tagged dependency links and error runs of collapse c (the stored fields), and the error
  // runs of every collapse.
  size_t dependency_link_count(size_t c) const;
  size_t error_run_count(size_t c) const;
  size_t error_run_count() const;

 private:
  std::shared_ptr<const detail::TdagData> data_;
  friend class TdagCut;
  friend Status build_temporal_dag(const AnimatedMeshView&, const TdagOptions&, TemporalDag&, TdagBuildReport*);
  friend Status deserialize_temporal_dag(const uint8_t*, size_t, TemporalDag&);
  friend Status load_temporal_dag(const std::string&, TemporalDag&, size_t);
  friend Status serialize_temporal_dag(const TemporalDag&, std::vector<uint8_t>&);
  friend Status write_temporal_dag(const TemporalDag&, TdagFileSink&, size_t);
};

// Builds the TDAG of `mesh` (Sections 3-4). The collapse orders come from the collapse engine
// (cpp/src/collapse_engine.hpp) with the TDAG's half-edge quadric policy, or from AQEM. Cost:
// governed, one decimation plus O(F (V depth + M)) for the per-frame fields; online, one
// decimation per frame.
//
// Any indexed triangle mesh is taken (see TdagOptions::weld). Errors (naming the element): no
// frames or faces, a non-finite position, a face index outside [0, V), every face degenerate;
// governing_frame outside [0, F); history_weight negative or not finite; for Governing::aqem,
// any error of simplify_animated. `out` is left empty on error; `report` (may be null) is
// filled on success.
Status build_temporal_dag(const AnimatedMeshView& mesh, const TdagOptions& options, TemporalDag& out,
                          TdagBuildReport* report = nullptr);

// The current version of the .tdag format written by serialize_temporal_dag (2: two-sided
// faces), and the oldest deserialize_temporal_dag reads.
constexpr uint32_t kTdagFormatVersion = 2;
constexpr uint32_t kTdagOldestReadableVersion = 1;

// The TDAG and its affine maps as bytes of the versioned .tdag format (little-endian, checksummed).
Status serialize_temporal_dag(const TemporalDag& dag, std::vector<uint8_t>& out);
// Reads bytes written by serialize_temporal_dag. Errors: not a TDAG (bad magic), a format
// version this build does not read (older or newer, both named), a truncated or corrupted
// file (checksum, sizes, out-of-range indices, dependencies that do not order a collapse after
// its children on some frame, naming the collapse, child and frame), each saying which. Cost:
// linear in the file, plus for the order check a search from each collapse through the ones
// ranked between it and its children (again on frames where the structure changes).
Status deserialize_temporal_dag(const uint8_t* bytes, size_t size, TemporalDag& out);
// Where write_temporal_dag puts a .tdag file: its bytes in order (`append`), then the body's
// length written over the 8 bytes at offset 12 (`overwrite`), which hold zeros until the body is
// complete. Each returns false when it could not write.
class TdagFileSink {
 public:
  virtual ~TdagFileSink() = default;
  virtual bool append(const uint8_t* bytes, size_t size) = 0;
  virtual bool overwrite(size_t offset, const uint8_t* bytes, size_t size) = 0;
};
// The bytes serialize_temporal_dag makes, handed to `sink` about `chunk_size` at a time (and
// long arrays as they are), so that a long clip's file is never held whole. Error "write failed"
// when the sink returns false.
Status write_temporal_dag(const TemporalDag& dag, TdagFileSink& sink, size_t chunk_size = size_t{1} << 20);
// File versions: the message of an error starts with the path. save writes `path` through a
// temporary file renamed into place. load reads the file twice, `chunk_size` bytes at a time
// (the memory it costs beyond the TDAG): once for the checksum, then into the fields.
Status save_temporal_dag(const TemporalDag& dag, const std::string& path);
Status load_temporal_dag(const std::string& path, TemporalDag& out, size_t chunk_size = size_t{1} << 20);

// The three temporal approximation levels of Section 5.
enum class ApproximationLevel : int {
  affine = 1,    // the previous cut and its residual positions, with the new frame's affine map
  residual = 2,  // the previous cut, the new frame's residual positions and affine map
  full = 3,      // the cut updated to the new frame, its residual positions and affine map
};

// A screen-space tolerance: a node may stand for its input vertices while its error bound,
// seen from `camera` (asset units, the frame's space) at the node's distance minus the bound,
// covers at most `pixels` pixels for a focal length of `focal_pixels` (viewport height / (2
// tan(fov_y / 2))).
struct ViewTolerance {
  double camera[3] = {0.0, 0.0, 0.0};
  double pixels = 1.0;
  double focal_pixels = 1000.0;
};

// A mesh handed out by a cut.
struct TdagMesh {
  int32_t frame = 0;             // frame of the affine map (and of the residuals, levels 2-3)
  int32_t cut_frame = 0;         // frame the cut was computed for
  int32_t residual_frame = 0;    // frame of the residual positions
  std::vector<float> positions;  // (V', 3) asset units
  std::vector<int32_t> faces;    // (M', 3) indices into positions, counter-clockwise; the
                                 // turned-over copies of two-sided faces follow the others
  std::vector<int32_t> nodes;    // (V',) hierarchy node of each vertex (< V: an input vertex)
  double error_bound = 0.0;      // largest bound of the active nodes at cut_frame (asset units)
};

// A cut of the TDAG: the state of one viewer of the sequence. Fresh queries build it from the
// hierarchy; advance() and refine() update it by splitting and collapsing only where the
// error bounds (or the tolerance) moved across the tolerance. Every update keeps the cut valid:
// the mesh is the one the same set of collapses gives when applied to the input. Not thread
// safe; several cuts of one TDAG may be used from different threads.
class TdagCut {
 public:
  explicit TdagCut(const TemporalDag& dag);
  ~TdagCut();
  TdagCut(TdagCut&&) noexcept;
  TdagCut& operator=(TdagCut&&) noexcept;
  TdagCut(const TdagCut&);  // copies the whole state (O(V + M))
  TdagCut& operator=(const TdagCut&);

  // Random query: the coarsest cut at `frame` whose bounds are all <= tolerance (asset units).
  // Errors: frame outside [0, F), tolerance negative or NaN.
  Status query(int32_t frame, double tolerance);
  // Random query with a screen-space tolerance per node (the coarsest valid cut in which
  // every active node meets its own tolerance). Errors: frame, pixels <= 0, focal <= 0,
  // non-finite camera.
  Status query_view(int32_t frame, const ViewTolerance& view);
  // Incremental in time: the cut for `frame` with the same tolerance (or view). Equal to a
  // fresh query. Errors: no query yet, frame outside [0, F).
  Status advance(int32_t frame);
  // Incremental in resolution: the cut for a new tolerance at the same frame.
  Status refine(double tolerance);
  // Incremental with a new screen-space tolerance (e.g. the camera moved).
  Status refine_view(const ViewTolerance& view);

  // Section 5: the mesh of `frame` at `level` (see ApproximationLevel). Level 3 advances the
  // cut; levels 1-2 leave it (level 2 remembers the residual frame it used, so a later level 1
  // reuses those positions).
  Status approximate(int32_t frame, ApproximationLevel level, TdagMesh& out);
  // The current cut at its frame (level 3 without moving).
  void mesh(TdagMesh& out) const;
  // (V,) for each input vertex (leaf 0 .. V-1, a TDAG vertex; compose with input_points() for the
  // caller's input_vertex_count() vertices), the index in mesh().positions of the vertex standing for it.
  void input_vertex_map(std::vector<int32_t>& out) const;

  int32_t frame() const;
  double tolerance() const;   // NaN in view mode
  bool has_query() const;
  size_t active_vertex_count() const;
  size_t active_face_count() const;
  double error_bound() const;  // largest bound of the active nodes (0 when all are input vertices)
  // Splits and collapses done by the last query or update.
  size_t last_split_count() const;
  size_t last_collapse_count() const;

 private:
  std::unique_ptr<detail::CutState> state_;
};

}  // namespace animlod
