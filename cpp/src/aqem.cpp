// AQEM: animated quadric error metric simplification (Yang et al. 2019, "Animated mesh
// simplification based on motion features in visual sensor networks").
//
// Implements the 12-step outline of the paper:
//   steps 1-2  per-vertex quadrics of every frame (Eqs. 1-4; block-diagonal, so F quadrics of
//              ten doubles per vertex, stored contiguously per vertex);
//   steps 3-4  motion features and vertex weights (motion_features.cpp);
//   steps 5-6  per edge: merged quadric Q = Q_i + Q_j (the text after Eq. 4; step 5.1 writes
//              (Q_i + Q_j) / 2, which only rescales), weight w = (w_i + w_j) / 2, optimal
//              position per frame (Eq. 5), cost w * sum_f Q_f(v_f) (Eq. 6);
//   step 7     an indexed min-heap of edges;
//   steps 8-12 pop, test legality (OpenMesh's link condition and Eq. 7's inversion test across
//              frames), collapse, pass the weight on, re-key the edges around the new vertex.
#include "animlod/aqem.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <OpenMesh/Core/Mesh/TriConnectivity.hh>

#include "animlod/mesh_validation.hpp"
#include "frame_sampling.hpp"
#include "indexed_heap.hpp"
#include "quadric.hpp"
#include "skin_merge.hpp"

namespace animlod {

namespace {

// Connectivity only: positions live in the per-vertex frame arrays, not in OpenMesh.
using TriMesh = OpenMesh::TriConnectivity;
using detail::Quadric;

// How an edge would collapse: `removed` merges into `kept`.
struct Candidate {
  int32_t kept = -1;
  int32_t removed = -1;
  double cost = 0.0;   // weighted cost of Eq. 6
  double error = 0.0;  // RMS distance to the merged quadric's planes over the used frames, asset units
  double t = 0.0;      // the new vertex is kept + t (removed - kept) in frames outside the quadrics
  double weight = 1.0; // (w_kept + w_removed) / 2, Eq. 6
};

// Checks the options against the mesh and resolves the level targets (finest first).
Status resolve_targets(const AnimatedMeshView& mesh, const AqemOptions& options, std::vector<size_t>& targets) {
  const size_t face_count = mesh.face_count;
  targets.clear();
  if (!options.target_face_counts.empty()) {
    for (size_t count : options.target_face_counts) {
      if (count < 4 || count > face_count)
        return Status::error("target_face_counts: " + std::to_string(count) + " outside [4, " +
                             std::to_string(face_count) + "] (the mesh has " + std::to_string(face_count) +
                             " faces)");
      targets.push_back(count);
    }
  } else {
    for (double ratio : options.target_ratios) {
      if (!(ratio > 0.0 && ratio <= 1.0))
        return Status::error("target_ratios: " + std::to_string(ratio) + " outside (0, 1]");
      const auto count = static_cast<size_t>(std::llround(ratio * static_cast<double>(face_count)));
      if (count < 4)
        return Status::error("target_ratios: " + std::to_string(ratio) + " of " + std::to_string(face_count) +
                             " faces is below 4 faces");
      targets.push_back(count);
    }
  }
  if (targets.empty()) return Status::error("target_ratios: no level requested");
  std::sort(targets.begin(), targets.end(), std::greater<>());
  if (std::isnan(options.max_error) || options.max_error < 0.0)
    return Status::error("max_error: must be >= 0");
  return Status::success();
}

Status resolve_frames(const AnimatedMeshView& mesh, const AqemOptions& options, std::vector<int32_t>& frames) {
  if (!options.frame_subset.empty()) {
    frames = options.frame_subset;
    for (int32_t f : frames)
      if (f < 0 || static_cast<size_t>(f) >= mesh.frame_count)
        return Status::error("frame_subset: frame " + std::to_string(f) + " outside [0, " +
                             std::to_string(mesh.frame_count) + ")");
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  } else if (options.max_frames > 0 && options.max_frames < mesh.frame_count) {
    frames = detail::sample_frames(mesh, options.max_frames);
  } else {
    frames.resize(mesh.frame_count);
    for (size_t f = 0; f < mesh.frame_count; ++f) frames[f] = static_cast<int32_t>(f);
  }
  return Status::success();
}

// The pointers and counts must agree before any value is read.
Status validate_vertex_data_layout(const AqemVertexData& data) {
  if (data.attribute_count > 0 && !data.attributes)
    return Status::error("attributes: attribute_count is " + std::to_string(data.attribute_count) +
                         " but attributes is null");
  if ((data.skin_joints == nullptr) != (data.skin_weights == nullptr))
    return Status::error("skin_joints and skin_weights: give both or neither");
  return Status::success();
}

Status validate_vertex_data(const AnimatedMeshView& mesh, const AqemVertexData& data) {
  if (Status status = validate_vertex_data_layout(data); !status) return status;
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    if (data.importance && !(std::isfinite(data.importance[v]) && data.importance[v] > 0.0f))
      return Status::error("importance: vertex " + std::to_string(v) + " has a non-positive or non-finite weight");
    for (size_t a = 0; a < data.attribute_count; ++a)
      if (!std::isfinite(data.attributes[v * data.attribute_count + a]))
        return Status::error("attributes: vertex " + std::to_string(v) + " has a non-finite value");
    for (size_t k = 0; k < data.influence_count && data.skin_joints; ++k) {
      const size_t i = v * data.influence_count + k;
      if (data.skin_joints[i] < 0)
        return Status::error("skin_joints: vertex " + std::to_string(v) + " has a negative joint index");
      if (!(std::isfinite(data.skin_weights[i]) && data.skin_weights[i] >= 0.0f))
        return Status::error("skin_weights: vertex " + std::to_string(v) + " has a negative or non-finite weight");
    }
  }
  return Status::success();
}

class Simplifier {
 public:
  Simplifier(const AnimatedMeshView& mesh, const AqemVertexData& data, const AqemOptions& options,
             std::vector<int32_t> frames, std::vector<float> weights)
      : mesh_(mesh),
        data_(data),
        options_(options),
        frames_(std::move(frames)),
        frame_count_(mesh.frame_count),
        used_count_(frames_.size()),
        vertex_weights_(weights.begin(), weights.end()),
        merged_into_(mesh.vertex_count),
        new_positions_(used_count_),
        singular_(used_count_),
        placed_(frame_count_) {}

  Status run(const std::vector<size_t>& targets, AqemResult& out);

 private:
  Status build_connectivity();
  void accumulate_quadrics();
  Candidate evaluate(int32_t edge);
  double rms_plane_distance(const Candidate& candidate, double total) const;
  Candidate evaluate_on_edge(Candidate candidate, bool pinned);
  bool is_legal(const Candidate& candidate, TriMesh::HalfedgeHandle collapse);
  void place_in_every_frame(const Candidate& candidate);
  bool keeps_orientation(const Candidate& candidate);
  void collapse(const Candidate& candidate, TriMesh::HalfedgeHandle halfedge, CollapseRecord& record);
  void rekey_around(TriMesh::VertexHandle vertex, bool all_edges);
  void park(int32_t edge);
  AqemLevel snapshot(size_t target, bool reached);

  Eigen::Vector3d position(int32_t vertex, size_t frame) const {
    const float* p = &positions_[(static_cast<size_t>(vertex) * frame_count_ + frame) * 3];
    return {p[0], p[1], p[2]};
  }
  bool locked(int32_t vertex) const { return data_.locked && data_.locked[vertex]; }
  Quadric* quadrics_of(int32_t vertex) { return &quadrics_[static_cast<size_t>(vertex) * used_count_]; }

  const AnimatedMeshView& mesh_;
  const AqemVertexData& data_;
  const AqemOptions& options_;
  const std::vector<int32_t> frames_;  // frames whose quadrics are used (K)
  const size_t frame_count_;           // F
  const size_t used_count_;            // K
  std::vector<double> vertex_weights_; // (V,) Eq. 6 weights, passed on by collapses (step 9)
  std::vector<float> positions_;       // (V, F, 3) current positions, contiguous per vertex
  std::vector<Quadric> quadrics_;      // (V, K) per-frame quadrics, contiguous per vertex
  std::vector<double> plane_counts_;   // (V,) planes summed into each of the vertex's K quadrics
  std::vector<float> attributes_;      // (V, A)
  std::vector<int32_t> skin_joints_;   // (V, K)
  std::vector<float> skin_weights_;    // (V, K)
  std::vector<int32_t> merged_into_;   // (V,) a vertex each removed vertex merged into (directly or not)
  std::vector<uint8_t> parked_;        // (E,) popped while illegal; re-tried when the area changes
  std::vector<uint8_t> may_have_parked_;  // (V,) set when an edge of the vertex is parked
  std::vector<Eigen::Vector3d> new_positions_;  // (K,) placement of the candidate being evaluated
  std::vector<uint8_t> singular_;               // (K,) frames of that candidate using the fallback
  std::vector<Eigen::Vector3d> placed_;         // (F,) its position in every frame (place_in_every_frame)
  TriMesh connectivity_;
  detail::IndexedMinHeap heap_{0};
  size_t face_count_ = 0;
  double error_so_far_ = 0.0;
  size_t collapse_count_ = 0;
};

Status Simplifier::build_connectivity() {
  connectivity_.request_vertex_status();
  connectivity_.request_edge_status();
  connectivity_.request_face_status();
  std::vector<TriMesh::VertexHandle> handles(mesh_.vertex_count);
  for (size_t v = 0; v < mesh_.vertex_count; ++v) handles[v] = connectivity_.new_vertex();
  for (size_t f = 0; f < mesh_.face_count; ++f) {
    const int32_t* v = mesh_.faces + 3 * f;
    if (!connectivity_.add_face(handles[v[0]], handles[v[1]], handles[v[2]]).is_valid())
      return Status::error("face " + std::to_string(f) + ": OpenMesh cannot add it to the halfedge mesh");
  }
  face_count_ = mesh_.face_count;
  return Status::success();
}

// Steps 1-2 (Eqs. 1-4): every face's plane in every used frame goes into its three vertices'
// quadrics of that frame; boundary edges add a perpendicular plane (option boundary_quadrics).
// plane_counts_ counts the planes of each vertex, so that the error can be a mean; a face with
// no area in a frame counts there as a plane at distance 0.
void Simplifier::accumulate_quadrics() {
  quadrics_.assign(mesh_.vertex_count * used_count_, Quadric{});
  plane_counts_.assign(mesh_.vertex_count, 0.0);
  for (size_t f = 0; f < mesh_.face_count; ++f) {
    const int32_t* v = mesh_.faces + 3 * f;
    for (int corner = 0; corner < 3; ++corner) plane_counts_[v[corner]] += 1.0;
    for (size_t k = 0; k < used_count_; ++k) {
      const size_t frame = static_cast<size_t>(frames_[k]);
      const Eigen::Vector3d p0 = position(v[0], frame), p1 = position(v[1], frame), p2 = position(v[2], frame);
      const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
      const double length = normal.norm();
      if (length == 0.0) continue;  // a face with no area in this frame has no plane
      const Quadric plane = Quadric::plane(normal / length, p0, 1.0);
      for (int corner = 0; corner < 3; ++corner) quadrics_of(v[corner])[k] += plane;
    }
  }
  if (!options_.boundary_quadrics) return;
  for (const auto halfedge : connectivity_.halfedges()) {
    if (!halfedge.is_boundary()) continue;
    const int32_t a = halfedge.from().idx(), b = halfedge.to().idx();
    const int32_t c = halfedge.opp().next().to().idx();  // third vertex of the face on the other side
    plane_counts_[a] += 1.0;
    plane_counts_[b] += 1.0;
    for (size_t k = 0; k < used_count_; ++k) {
      const size_t frame = static_cast<size_t>(frames_[k]);
      const Eigen::Vector3d pa = position(a, frame), pb = position(b, frame), pc = position(c, frame);
      const Eigen::Vector3d face_normal = (pb - pa).cross(pc - pa);
      const Eigen::Vector3d normal = (pb - pa).cross(face_normal);
      const double length = normal.norm();
      if (length == 0.0) continue;
      const Quadric plane = Quadric::plane(normal / length, pa, 1.0);
      quadrics_of(a)[k] += plane;
      quadrics_of(b)[k] += plane;
    }
  }
}

// Steps 5-6: merged quadric, weight and optimal placement per used frame (Eq. 5); cost of
// Eq. 6. Frames whose X is singular share one fallback, the best in sum over those frames of
// the kept endpoint, the removed endpoint and the midpoint (ties in that order), so that the
// vertex does not slide to a different point of a flat region in every frame. Leaves the
// placement in new_positions_.
Candidate Simplifier::evaluate(int32_t edge) {
  const auto halfedge = connectivity_.halfedge_handle(connectivity_.edge_handle(edge), 0);
  const int32_t a = connectivity_.from_vertex_handle(halfedge).idx();
  const int32_t b = connectivity_.to_vertex_handle(halfedge).idx();
  Candidate candidate;
  // The locked vertex survives; otherwise the lower index does, for determinism.
  const bool keep_a = locked(a) || (!locked(b) && a < b);
  candidate.kept = keep_a ? a : b;
  candidate.removed = keep_a ? b : a;
  candidate.weight = 0.5 * (vertex_weights_[a] + vertex_weights_[b]);
  const bool pinned = locked(candidate.kept);

  const Quadric* kept_quadrics = quadrics_of(candidate.kept);
  const Quadric* removed_quadrics = quadrics_of(candidate.removed);
  if (pinned || options_.placement == Placement::on_edge) return evaluate_on_edge(candidate, pinned);
  constexpr double kFallbacks[3] = {0.0, 1.0, 0.5};  // kept, removed, midpoint along the edge
  double fallback_cost[3] = {0.0, 0.0, 0.0};
  double total = 0.0;
  for (size_t k = 0; k < used_count_; ++k) {
    const size_t frame = static_cast<size_t>(frames_[k]);
    const Quadric merged = kept_quadrics[k] + removed_quadrics[k];
    Eigen::Vector3d& v = new_positions_[k];
    singular_[k] = !merged.minimizer(v);
    if (!singular_[k]) {
      total += merged.evaluate(v);
      continue;
    }
    const Eigen::Vector3d p_kept = position(candidate.kept, frame), p_removed = position(candidate.removed, frame);
    for (int option = 0; option < 3; ++option)
      fallback_cost[option] += merged.evaluate(p_kept + kFallbacks[option] * (p_removed - p_kept));
  }
  int fallback = 0;
  for (int option = 1; option < 3; ++option)
    if (fallback_cost[option] < fallback_cost[fallback]) fallback = option;
  total += fallback_cost[fallback];

  double along = 0.0, length2 = 0.0;
  for (size_t k = 0; k < used_count_; ++k) {
    const size_t frame = static_cast<size_t>(frames_[k]);
    const Eigen::Vector3d p_kept = position(candidate.kept, frame), p_removed = position(candidate.removed, frame);
    if (singular_[k]) new_positions_[k] = p_kept + kFallbacks[fallback] * (p_removed - p_kept);
    along += (new_positions_[k] - p_kept).dot(p_removed - p_kept);
    length2 += (p_removed - p_kept).squaredNorm();
  }
  candidate.t = length2 > 0.0 ? std::clamp(along / length2, 0.0, 1.0) : 0.0;
  candidate.cost = candidate.weight * total;
  candidate.error = rms_plane_distance(candidate, total);
  return candidate;
}

// The merged quadric's `total` (Eq. 6 unweighted: sum over the K frames of the squared
// distances to its planes) over K times its plane count: an RMS plane distance that does not
// grow with the number of planes merged.
double Simplifier::rms_plane_distance(const Candidate& candidate, double total) const {
  const double planes = plane_counts_[candidate.kept] + plane_counts_[candidate.removed];
  return std::sqrt(total / (static_cast<double>(used_count_) * planes));
}

// Placement::on_edge (and a locked kept vertex, t = 0): the t in [0, 1] minimising
// sum_f Q_f(kept_f + t (removed_f - kept_f)), a quadratic in t.
Candidate Simplifier::evaluate_on_edge(Candidate candidate, bool pinned) {
  const Quadric* kept_quadrics = quadrics_of(candidate.kept);
  const Quadric* removed_quadrics = quadrics_of(candidate.removed);
  double curvature = 0.0, slope = 0.0;
  if (!pinned) {
    for (size_t k = 0; k < used_count_; ++k) {
      const size_t frame = static_cast<size_t>(frames_[k]);
      const Eigen::Vector3d p_kept = position(candidate.kept, frame);
      (kept_quadrics[k] + removed_quadrics[k])
          .accumulate_line(p_kept, position(candidate.removed, frame) - p_kept, curvature, slope);
    }
  }
  candidate.t = curvature > 0.0 ? std::clamp(-slope / curvature, 0.0, 1.0) : (slope < 0.0 ? 1.0 : 0.0);
  double total = 0.0;
  for (size_t k = 0; k < used_count_; ++k) {
    const size_t frame = static_cast<size_t>(frames_[k]);
    const Eigen::Vector3d p_kept = position(candidate.kept, frame);
    new_positions_[k] = p_kept + candidate.t * (position(candidate.removed, frame) - p_kept);
    total += (kept_quadrics[k] + removed_quadrics[k]).evaluate(new_positions_[k]);
  }
  candidate.cost = candidate.weight * total;
  candidate.error = rms_plane_distance(candidate, total);
  return candidate;
}

// Eq. 7 for every face that survives around the collapse: sum_f n(t^f) . n(t'^f)
// sqrt(A(t^f) A(t'^f) w_t w_t') < 0 means inverted. The weights w_t, w_t' do not depend on the
// frame, so they cannot change the sign of one face's sum and are left out. A face whose area
// vanishes in every frame is rejected too; strict_inversion rejects a flip in any one frame.
// Every frame is tested, not only the quadrics' frames: the others get placed_ positions too.
bool Simplifier::keeps_orientation(const Candidate& candidate) {
  for (const int32_t moved : {candidate.kept, candidate.removed}) {
    const int32_t other = moved == candidate.kept ? candidate.removed : candidate.kept;
    for (const auto face : connectivity_.vf_range(connectivity_.vertex_handle(moved))) {
      int32_t corners[3];
      int corner = 0;
      bool collapses = false;
      for (const auto vertex : face.vertices()) {
        corners[corner++] = vertex.idx();
        collapses |= vertex.idx() == other;
      }
      if (collapses) continue;  // the two faces on the edge disappear
      double agreement = 0.0;
      bool has_area = false;
      for (size_t frame = 0; frame < frame_count_; ++frame) {
        Eigen::Vector3d before[3], after[3];
        for (int c = 0; c < 3; ++c) {
          before[c] = position(corners[c], frame);
          after[c] = corners[c] == moved ? placed_[frame] : before[c];
        }
        const Eigen::Vector3d n_before = (before[1] - before[0]).cross(before[2] - before[0]);
        const Eigen::Vector3d n_after = (after[1] - after[0]).cross(after[2] - after[0]);
        const double area_product = n_before.norm() * n_after.norm();
        if (area_product == 0.0) continue;
        has_area = true;
        const double dot = n_before.dot(n_after);
        if (options_.strict_inversion && dot < 0.0) return false;
        // n . n' sqrt(A A') with n = N / |N| and A = |N| / 2.
        agreement += dot / (2.0 * std::sqrt(area_product));
      }
      if (!has_area || agreement < 0.0) return false;
    }
  }
  return true;
}

bool Simplifier::is_legal(const Candidate& candidate, TriMesh::HalfedgeHandle collapse) {
  if (locked(candidate.removed)) return false;  // both endpoints locked
  if (!connectivity_.is_collapse_ok(collapse)) return false;
  // A valence-3 interior vertex beside the edge would be left with two faces on the same three
  // vertices (e.g. a tetrahedron folding flat); is_collapse_ok allows that.
  for (const auto side : {collapse, connectivity_.opposite_halfedge_handle(collapse)}) {
    if (connectivity_.is_boundary(side)) continue;
    const auto opposite = connectivity_.to_vertex_handle(connectivity_.next_halfedge_handle(side));
    if (!connectivity_.is_boundary(opposite) && connectivity_.valence(opposite) <= 3) return false;
  }
  return !options_.check_inversion || keeps_orientation(candidate);
}

// The candidate's vertex in every frame F: its Eq. 5 placement (new_positions_) in the
// quadrics' frames, kept + t (removed - kept) in the others.
void Simplifier::place_in_every_frame(const Candidate& candidate) {
  size_t used = 0;
  for (size_t frame = 0; frame < frame_count_; ++frame) {
    if (used < used_count_ && static_cast<size_t>(frames_[used]) == frame) {
      placed_[frame] = new_positions_[used++];
      continue;
    }
    const Eigen::Vector3d p_kept = position(candidate.kept, frame);
    placed_[frame] = p_kept + candidate.t * (position(candidate.removed, frame) - p_kept);
  }
}

// Steps 9-10: move the kept vertex to its placed_ positions in every frame, merge quadrics (the
// text after Eq. 4), weights (Eq. 6) and attributes, collapse, and re-key the affected edges.
void Simplifier::collapse(const Candidate& candidate, TriMesh::HalfedgeHandle halfedge, CollapseRecord& record) {
  record.removed.push_back(candidate.removed);
  record.kept.push_back(candidate.kept);
  record.cost.push_back(candidate.cost);
  record.error.push_back(candidate.error);

  for (size_t frame = 0; frame < frame_count_; ++frame) {
    float* out = &positions_[(static_cast<size_t>(candidate.kept) * frame_count_ + frame) * 3];
    for (int axis = 0; axis < 3; ++axis) {
      out[axis] = static_cast<float>(placed_[frame][axis]);
      record.positions.push_back(out[axis]);
    }
  }
  Quadric* kept_quadrics = quadrics_of(candidate.kept);
  const Quadric* removed_quadrics = quadrics_of(candidate.removed);
  for (size_t k = 0; k < used_count_; ++k) kept_quadrics[k] += removed_quadrics[k];
  plane_counts_[candidate.kept] += plane_counts_[candidate.removed];
  vertex_weights_[candidate.kept] = candidate.weight;
  const size_t attribute_count = data_.attribute_count;
  for (size_t a = 0; a < attribute_count; ++a) {
    float& kept = attributes_[candidate.kept * attribute_count + a];
    kept += static_cast<float>(candidate.t) * (attributes_[candidate.removed * attribute_count + a] - kept);
  }
  if (!skin_joints_.empty()) {
    const size_t k = data_.influence_count;
    detail::merge_skin_weights(&skin_joints_[candidate.kept * k], &skin_weights_[candidate.kept * k],
                               &skin_joints_[candidate.removed * k], &skin_weights_[candidate.removed * k], k,
                               candidate.t);
  }
  merged_into_[candidate.removed] = candidate.kept;
  ++collapse_count_;

  // Connectivity: the edges of the removed vertex either move to the kept one or vanish.
  const auto removed = connectivity_.vertex_handle(candidate.removed);
  std::vector<int32_t> old_edges;
  for (const auto edge : connectivity_.ve_range(removed)) old_edges.push_back(edge.idx());
  face_count_ -= connectivity_.is_boundary(connectivity_.edge_handle(halfedge)) ? 1 : 2;
  connectivity_.collapse(halfedge);
  for (int32_t edge : old_edges)
    if (connectivity_.status(connectivity_.edge_handle(edge)).deleted()) heap_.remove(edge);

  // Step 10: the costs of the edges at the kept vertex changed; the legality of edges one ring
  // further may have changed, so parked edges there are tried again.
  const auto kept = connectivity_.vertex_handle(candidate.kept);
  rekey_around(kept, true);
  for (const auto neighbour : connectivity_.vv_range(kept)) rekey_around(neighbour, false);
}

// Re-evaluates the edges at `vertex`: all of them when its quadric changed, otherwise only
// the parked ones (their cost is unchanged, but their legality may have changed).
void Simplifier::rekey_around(TriMesh::VertexHandle vertex, bool all_edges) {
  if (!all_edges && !may_have_parked_[vertex.idx()]) return;
  may_have_parked_[vertex.idx()] = 0;
  for (const auto edge : connectivity_.ve_range(vertex)) {
    const int32_t e = edge.idx();
    if (!all_edges && !parked_[e]) continue;
    parked_[e] = 0;
    if (locked(edge.v0().idx()) && locked(edge.v1().idx())) continue;  // can never collapse
    heap_.set(e, evaluate(e).cost);
  }
}

void Simplifier::park(int32_t edge) {
  heap_.remove(edge);
  parked_[edge] = 1;
  const auto handle = connectivity_.edge_handle(edge);
  may_have_parked_[connectivity_.to_vertex_handle(connectivity_.halfedge_handle(handle, 0)).idx()] = 1;
  may_have_parked_[connectivity_.to_vertex_handle(connectivity_.halfedge_handle(handle, 1)).idx()] = 1;
}

AqemLevel Simplifier::snapshot(size_t target, bool reached) {
  AqemLevel level;
  level.target_face_count = target;
  level.reached = reached;
  level.error = error_so_far_;
  level.collapse_count = collapse_count_;
  const size_t vertex_count = mesh_.vertex_count;
  std::vector<int32_t> new_index(vertex_count, -1);
  for (size_t v = 0; v < vertex_count; ++v) {
    if (connectivity_.status(connectivity_.vertex_handle(static_cast<int>(v))).deleted()) continue;
    new_index[v] = static_cast<int32_t>(level.kept_vertices.size());
    level.kept_vertices.push_back(static_cast<int32_t>(v));
  }
  level.vertex_map.resize(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    int32_t root = static_cast<int32_t>(v);
    while (merged_into_[root] != root) root = merged_into_[root];
    // Path compression: later snapshots follow one link.
    for (int32_t x = static_cast<int32_t>(v); merged_into_[x] != root;) x = std::exchange(merged_into_[x], root);
    level.vertex_map[v] = new_index[root];
  }
  for (const auto face : connectivity_.faces()) {
    if (connectivity_.status(face).deleted()) continue;
    for (const auto vertex : face.vertices()) level.faces.push_back(new_index[vertex.idx()]);
  }
  const size_t kept_count = level.kept_vertices.size();
  level.positions.resize(frame_count_ * kept_count * 3);
  for (size_t i = 0; i < kept_count; ++i) {
    const float* source = &positions_[static_cast<size_t>(level.kept_vertices[i]) * frame_count_ * 3];
    for (size_t frame = 0; frame < frame_count_; ++frame)
      std::copy_n(source + frame * 3, 3, &level.positions[(frame * kept_count + i) * 3]);
  }
  auto gather = [&](const auto& source, size_t width, auto& destination) {
    destination.resize(kept_count * width);
    // data() rather than &v[0]: an absent attribute set is an empty vector, and indexing it is UB.
    for (size_t i = 0; i < kept_count; ++i)
      std::copy_n(source.data() + static_cast<size_t>(level.kept_vertices[i]) * width, width,
                  destination.data() + i * width);
  };
  gather(attributes_, data_.attribute_count, level.attributes);
  if (!skin_joints_.empty()) {
    gather(skin_joints_, data_.influence_count, level.skin_joints);
    gather(skin_weights_, data_.influence_count, level.skin_weights);
  }
  return level;
}

Status Simplifier::run(const std::vector<size_t>& targets, AqemResult& out) {
  // Working copies, laid out per vertex: (F, V, 3) -> (V, F, 3).
  const size_t vertex_count = mesh_.vertex_count;
  positions_.resize(vertex_count * frame_count_ * 3);
  for (size_t frame = 0; frame < frame_count_; ++frame)
    for (size_t v = 0; v < vertex_count; ++v)
      std::copy_n(mesh_.frames + (frame * vertex_count + v) * 3, 3, &positions_[(v * frame_count_ + frame) * 3]);
  if (data_.attributes) attributes_.assign(data_.attributes, data_.attributes + vertex_count * data_.attribute_count);
  if (data_.skin_joints) {
    skin_joints_.assign(data_.skin_joints, data_.skin_joints + vertex_count * data_.influence_count);
    skin_weights_.assign(data_.skin_weights, data_.skin_weights + vertex_count * data_.influence_count);
  }
  for (size_t v = 0; v < vertex_count; ++v) merged_into_[v] = static_cast<int32_t>(v);

  if (Status status = build_connectivity(); !status) return status;
  accumulate_quadrics();

  // Step 7: every collapsible edge into the heap.
  const size_t edge_count = connectivity_.n_edges();
  heap_ = detail::IndexedMinHeap(edge_count);
  parked_.assign(edge_count, 0);
  may_have_parked_.assign(vertex_count, 0);
  std::vector<int32_t> ids;
  std::vector<double> keys;
  ids.reserve(edge_count);
  keys.reserve(edge_count);
  for (const auto edge : connectivity_.edges()) {
    if (locked(edge.v0().idx()) && locked(edge.v1().idx())) continue;  // can never collapse
    ids.push_back(edge.idx());
    keys.push_back(evaluate(edge.idx()).cost);
  }
  heap_.assign(ids, keys);

  // Steps 8-12, taking a level each time the face count reaches a target.
  const size_t planned = (mesh_.face_count - targets.back() + 1) / 2;
  size_t next_level = 0;
  auto take_reached_levels = [&] {
    for (; next_level < targets.size() && face_count_ <= targets[next_level]; ++next_level)
      out.levels.push_back(snapshot(targets[next_level], true));
  };
  take_reached_levels();
  if (options_.progress) options_.progress(0, planned);
  while (next_level < targets.size() && !heap_.empty()) {
    const int32_t edge = heap_.top();
    const Candidate candidate = evaluate(edge);
    place_in_every_frame(candidate);
    // The halfedge from the removed vertex to the kept one (OpenMesh keeps the "to" vertex).
    auto halfedge = connectivity_.halfedge_handle(connectivity_.edge_handle(edge), 0);
    if (connectivity_.from_vertex_handle(halfedge).idx() != candidate.removed)
      halfedge = connectivity_.opposite_halfedge_handle(halfedge);
    if (!is_legal(candidate, halfedge)) {
      park(edge);
      continue;
    }
    if (candidate.error > options_.max_error) break;
    error_so_far_ = std::max(error_so_far_, candidate.error);
    collapse(candidate, halfedge, out.collapses);
    take_reached_levels();
    if (options_.progress && collapse_count_ % 4096 == 0) options_.progress(collapse_count_, planned);
  }
  for (; next_level < targets.size(); ++next_level) out.levels.push_back(snapshot(targets[next_level], false));
  if (options_.progress) options_.progress(collapse_count_, planned);
  out.vertex_weights.assign(vertex_weights_.begin(), vertex_weights_.end());
  return Status::success();
}

}  // namespace

Status simplify_animated(const AnimatedMeshView& mesh, const AqemVertexData& vertex_data, const AqemOptions& options,
                         AqemResult& out) {
  // Everything is built in `result` and moved into `out` only on success, so that an error
  // (or an exception from the progress callback) leaves `out` empty, never half filled.
  out = AqemResult{};
  AqemResult result;
  // The cheap O(V) check first; the mesh checks inside compute_motion_features cost O(M log M + F V).
  if (Status status = validate_vertex_data(mesh, vertex_data); !status) return status;
  // Steps 3-4: motion features give the vertex weights of Eq. 6 (their extraction validates
  // the mesh too); importance multiplies them.
  MotionFeatures features;
  const Status valid = options.use_motion_features ? compute_motion_features(mesh, options.motion_features, features)
                                                   : validate_animated_mesh(mesh);
  if (!valid) return valid;
  std::vector<size_t> targets;
  if (Status status = resolve_targets(mesh, options, targets); !status) return status;
  if (Status status = resolve_frames(mesh, options, result.frames_used); !status) return status;
  std::vector<float> weights = options.use_motion_features ? std::move(features.vertex_weights)
                                                           : std::vector<float>(mesh.vertex_count, 1.0f);
  if (vertex_data.importance)
    for (size_t v = 0; v < mesh.vertex_count; ++v) weights[v] *= vertex_data.importance[v];

  Simplifier simplifier(mesh, vertex_data, options, result.frames_used, std::move(weights));
  if (Status status = simplifier.run(targets, result); !status) return status;
  out = std::move(result);
  return Status::success();
}

}  // namespace animlod
