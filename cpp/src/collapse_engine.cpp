// The collapse loop of Yang et al. 2019's 12-step outline, steps 7-12 (an indexed min-heap of
// edges; pop, test legality, collapse, re-key), for any cost and placement policy.
#include "collapse_engine.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <iterator>
#include <limits>
#include <utility>

#include "bit_scan.hpp"
#include "cost_order.hpp"
#include "interior_collapse.hpp"
#include "inversion_test.hpp"
#include "phase_timer.hpp"
#include "skin_merge.hpp"
#include "worker_threads.hpp"

namespace animlod::detail {

CollapseEngine::CollapseEngine(const AnimatedMeshView& mesh, const PreparedMesh& prepared, const CarriedData& data,
                               const EngineOptions& options)
    : mesh_(mesh),
      prepared_(prepared),
      data_(data),
      options_(options),
      frame_count_(mesh.frame_count),
      point_count_(prepared.point_source.size()) {
  for (Workspace& workspace : workspaces_) workspace.placed.resize(frame_count_);
  // Working copies, laid out per point: (F, V, 3) -> (P, F, 3).
  positions_.resize(point_count_ * frame_count_ * 3);
  for (size_t frame = 0; frame < frame_count_; ++frame)
    for (size_t p = 0; p < point_count_; ++p)
      std::copy_n(mesh_.frames + (frame * mesh_.vertex_count + static_cast<size_t>(prepared_.point_source[p])) * 3, 3,
                  &positions_[(p * frame_count_ + frame) * 3]);
  locked_.resize(point_count_);
  for (size_t p = 0; p < point_count_; ++p) locked_[p] = prepared_.point_split[p] ? kLocked : 0;
  for (size_t v = 0; v < mesh_.vertex_count; ++v) {
    const int32_t point = prepared_.wedge_point[v];
    if (point < 0) continue;
    if (data_.locked && data_.locked[v]) locked_[point] = kLocked;
    else if (data_.guarded && data_.guarded[v] && locked_[point] == 0) locked_[point] = kGuarded;
  }
  if (data_.attributes)
    attributes_.assign(data_.attributes, data_.attributes + mesh_.vertex_count * data_.attribute_count);
  auto gather_by_point = [&](const auto* source, size_t width, auto& destination) {
    destination.resize(point_count_ * width);
    for (size_t p = 0; p < point_count_; ++p)
      std::copy_n(source + static_cast<size_t>(prepared_.point_source[p]) * width, width,
                  destination.data() + p * width);
  };
  if (data_.position_attributes)
    gather_by_point(data_.position_attributes, data_.position_attribute_count, position_attributes_);
  if (data_.skin_joints) {
    gather_by_point(data_.skin_joints, data_.influence_count, skin_joints_);
    gather_by_point(data_.skin_weights, data_.influence_count, skin_weights_);
  }
  corner_points_ = prepared_.faces;
  corner_wedges_ = prepared_.corner_wedges;
  merged_into_.resize(point_count_);
  for (size_t p = 0; p < point_count_; ++p) merged_into_[p] = static_cast<int32_t>(p);
  wedge_merged_into_.resize(mesh_.vertex_count);
  for (size_t v = 0; v < mesh_.vertex_count; ++v) wedge_merged_into_[v] = static_cast<int32_t>(v);
  build_connectivity();
  find_border_and_seam_sides();
}

// prepare_mesh guarantees a manifold, consistently oriented face set, so every face is added.
void CollapseEngine::build_connectivity() {
  connectivity_.request_vertex_status();
  connectivity_.request_edge_status();
  connectivity_.request_face_status();
  const size_t face_count = corner_points_.size() / 3;
  if (!prepared_.side_partners.empty()) {
    link_paired_sides();
  } else {
    connectivity_.reserve(point_count_, face_count * 3 / 2 + point_count_, face_count);
    connectivity_.resize(point_count_, 0, 0);
    for (size_t f = 0; f < face_count; ++f) {
      const int32_t* v = &corner_points_[3 * f];
      [[maybe_unused]] const auto face =
          connectivity_.add_face(connectivity_.vertex_handle(v[0]), connectivity_.vertex_handle(v[1]),
                                 connectivity_.vertex_handle(v[2]));
      assert(face.is_valid() && face.idx() == static_cast<int>(f));
    }
  }
  face_count_ = face_count;
  valence_.resize(point_count_);
  for (size_t p = 0; p < point_count_; ++p)
    valence_[p] = static_cast<int32_t>(connectivity_.valence(connectivity_.vertex_handle(static_cast<int>(p))));
  point_wedge_.assign(point_count_, -2);  // -2: no corner seen yet
  for (size_t c = 0; c < corner_points_.size(); ++c) {
    int32_t& wedge = point_wedge_[corner_points_[c]];
    wedge = wedge == -2 || wedge == corner_wedges_[c] ? corner_wedges_[c] : -1;
  }
}

// The halfedge structure add_face builds face by face, linked directly from prepare_mesh's
// paired sides instead (add_face searches the fan of each corner's point for every side), with
// every element created at once: edges numbered in order of their first side, halfedge 0
// running that side's way; a face's halfedge is its side into its first corner; a border
// halfedge is followed by the border halfedge leaving its end point (one per point: the fans
// are simple), which is also that point's outgoing halfedge, as add_face leaves it. An inner
// point's outgoing halfedge may differ from add_face's, which changes only where circulators
// start.
void CollapseEngine::link_paired_sides() {
  const std::vector<int32_t>& partners = prepared_.side_partners;
  const size_t corner_count = corner_points_.size();
  auto vertex = [&](size_t c) { return connectivity_.vertex_handle(corner_points_[c]); };
  std::vector<TriMesh::HalfedgeHandle> sides(corner_count);  // the halfedge of each corner's side
  int edge_count = 0;
  for (size_t c = 0; c < corner_count; ++c) {
    const int32_t partner = partners[c];
    sides[c] = partner < 0 || static_cast<size_t>(partner) > c
                   ? connectivity_.s_halfedge_handle(TriMesh::EdgeHandle(edge_count++), 0)
                   : connectivity_.opposite_halfedge_handle(sides[static_cast<size_t>(partner)]);
  }
  // Every element at once (new_edge and new_face resize every property per element).
  connectivity_.resize(point_count_, static_cast<size_t>(edge_count), corner_count / 3);
  std::vector<TriMesh::HalfedgeHandle> border_out(point_count_);  // invalid: an inner point
  for (size_t c = 0; c < corner_count; c += 3) {
    const auto face = connectivity_.face_handle(static_cast<int>(c / 3));
    connectivity_.set_halfedge_handle(face, sides[c + 2]);
    for (size_t k = c; k < c + 3; ++k) {
      connectivity_.set_vertex_handle(sides[k], vertex(next_corner(k)));
      connectivity_.set_face_handle(sides[k], face);
      connectivity_.set_next_halfedge_handle(sides[k], sides[next_corner(k)]);
      connectivity_.set_halfedge_handle(vertex(k), sides[k]);
      if (partners[k] >= 0) continue;
      const auto border = connectivity_.opposite_halfedge_handle(sides[k]);
      connectivity_.set_vertex_handle(border, vertex(k));
      border_out[static_cast<size_t>(corner_points_[next_corner(k)])] = border;
    }
  }
  for (size_t c = 0; c < corner_count; ++c) {
    if (partners[c] >= 0) continue;
    // The border halfedge opposite side c runs into corner c's point.
    connectivity_.set_next_halfedge_handle(connectivity_.opposite_halfedge_handle(sides[c]),
                                           border_out[static_cast<size_t>(corner_points_[c])]);
  }
  for (size_t p = 0; p < point_count_; ++p)
    if (border_out[p].is_valid())
      connectivity_.set_halfedge_handle(connectivity_.vertex_handle(static_cast<int>(p)), border_out[p]);
}

void CollapseEngine::find_border_and_seam_sides() {
  for (const auto halfedge : connectivity_.halfedges()) {
    if (!halfedge.is_boundary()) continue;
    border_sides_.push_back({halfedge.from().idx(), halfedge.to().idx(), halfedge.opp().next().to().idx()});
  }
  for (const auto edge : connectivity_.edges()) {
    if (edge.is_boundary()) continue;
    const auto h = edge.h0();
    const auto left = h.face(), right = h.opp().face();
    const int32_t a = h.from().idx(), b = h.to().idx();
    if (point_wedge_[a] >= 0 && point_wedge_[b] >= 0) continue;  // one wedge at each end
    if (corner_wedge(left, a) == corner_wedge(right, a) && corner_wedge(left, b) == corner_wedge(right, b)) continue;
    // A plane through the edge perpendicular to each face keeps the seam line in place.
    seam_sides_.push_back({a, b, h.next().to().idx()});
    seam_sides_.push_back({b, a, h.opp().next().to().idx()});
  }
}

int32_t CollapseEngine::corner_wedge(TriMesh::FaceHandle face, int32_t point) const {
  const size_t base = 3 * static_cast<size_t>(face.idx());
  for (size_t c = 0; c < 3; ++c)
    if (corner_points_[base + c] == point) return corner_wedges_[base + c];
  return -1;
}

// The locked point survives; otherwise the lower index does, for determinism.
Candidate CollapseEngine::candidate_for(int32_t edge) const {
  const auto halfedge = connectivity_.halfedge_handle(connectivity_.edge_handle(edge), 0);
  const int32_t a = connectivity_.from_vertex_handle(halfedge).idx();
  const int32_t b = connectivity_.to_vertex_handle(halfedge).idx();
  Candidate candidate;
  const bool keep_a = locked(a) || (!locked(b) && a < b);
  candidate.kept = keep_a ? a : b;
  candidate.removed = keep_a ? b : a;
  return candidate;
}

Candidate CollapseEngine::evaluate(CollapsePolicy& policy, int32_t edge) const {
  Candidate candidate = candidate_for(edge);
  policy.evaluate(candidate);
  return candidate;
}

// Seams: every wedge of the removed point must go to the kept point's wedge on the same side of
// the collapsed edge. The faces on the edge define the mapping (one pair per side); a wedge of
// the removed point that no side defines (it lies on another seam), or a side that would send
// one wedge to two, makes the collapse illegal. Leaves the mapping in workspace.wedge_moves.
bool CollapseEngine::map_wedges(const Candidate& candidate, TriMesh::HalfedgeHandle collapse,
                                Workspace& workspace) const {
  auto& wedge_moves = workspace.wedge_moves;
  wedge_moves.clear();
  // Two points without seams: every corner of the removed point takes the kept point's wedge.
  if (point_wedge_[candidate.removed] >= 0 && point_wedge_[candidate.kept] >= 0) {
    wedge_moves.emplace_back(point_wedge_[candidate.removed], point_wedge_[candidate.kept]);
    return true;
  }
  for (const auto side : {collapse, connectivity_.opposite_halfedge_handle(collapse)}) {
    const auto face = connectivity_.face_handle(side);
    if (!face.is_valid()) continue;
    const int32_t from = corner_wedge(face, candidate.removed), to = corner_wedge(face, candidate.kept);
    const auto known = std::find_if(wedge_moves.begin(), wedge_moves.end(),
                                    [from](const auto& move) { return move.first == from; });
    if (known == wedge_moves.end()) wedge_moves.emplace_back(from, to);
    else if (known->second != to) return false;
  }
  for (const auto face : connectivity_.vf_range(connectivity_.vertex_handle(candidate.removed))) {
    const int32_t wedge = corner_wedge(face, candidate.removed);
    const bool mapped = std::any_of(wedge_moves.begin(), wedge_moves.end(),
                                    [wedge](const auto& move) { return move.first == wedge; });
    if (!mapped) return false;
  }
  return true;
}

bool CollapseEngine::is_legal_connectivity(const Candidate& candidate, TriMesh::HalfedgeHandle collapse,
                                           Workspace& workspace) {
  if (locked(candidate.removed)) return false;  // both endpoints locked
  if (!connectivity_.is_collapse_ok(collapse)) return false;
  // A valence-3 interior vertex beside the edge would be left with two faces on the same three
  // vertices (e.g. a tetrahedron folding flat); is_collapse_ok allows that.
  for (const auto side : {collapse, connectivity_.opposite_halfedge_handle(collapse)}) {
    if (connectivity_.is_boundary(side)) continue;
    const auto opposite = connectivity_.to_vertex_handle(connectivity_.next_halfedge_handle(side));
    assert(valence_[opposite.idx()] == static_cast<int32_t>(connectivity_.valence(opposite)));

    if (valence_[opposite.idx()] <= 3 && !connectivity_.is_boundary(opposite)) return false;
  }
  return map_wedges(candidate, collapse, workspace);
}

bool CollapseEngine::keeps_orientation(const Candidate& candidate, const Workspace& workspace) const {
  if (!options_.check_inversion) return true;
  // Eq. 7 for every face that survives around the collapse, in every frame F: the kept and the
  // removed point both move to workspace.placed.
  for (const int32_t moved : {candidate.kept, candidate.removed}) {
    const int32_t other = moved == candidate.kept ? candidate.removed : candidate.kept;
    // The faces around `moved` by its outgoing halfedges, not by OpenMesh's face circulator,
    // whose bookkeeping cost as much as the test (the test's outcome does not depend on order).
    const auto first_out = connectivity_.halfedge_handle(connectivity_.vertex_handle(moved));
    auto out = first_out;
    do {
      const auto face = connectivity_.face_handle(out);
      out = connectivity_.cw_rotated_halfedge_handle(out);
      if (!face.is_valid()) continue;
      std::array<const float*, 3> corners{};
      int moved_corner = -1;
      bool collapses = false;
      // The flat corner array, not OpenMesh's face circulator, read from the corner OpenMesh
      // starts at (the same rounding in the test as before).
      const int32_t* face_points = &corner_points_[3 * static_cast<size_t>(face.idx())];
      const int32_t first = connectivity_.to_vertex_handle(connectivity_.halfedge_handle(face)).idx();
      const int start = face_points[0] == first ? 0 : face_points[1] == first ? 1 : 2;
      for (int corner = 0; corner < 3; ++corner) {
        const int32_t point = face_points[start + corner < 3 ? start + corner : start + corner - 3];
        if (point == moved) moved_corner = corner;
        collapses |= point == other;
        corners[corner] = &positions_[static_cast<size_t>(point) * frame_count_ * 3];
      }
      if (collapses) continue;  // the faces on the edge disappear
      if (!face_keeps_orientation(corners, moved_corner, workspace.placed.data(), frame_count_,
                                  options_.fold_limit))
        return false;
    } while (out != first_out);
  }
  return true;
}

// Step 9: move the kept point to workspace.placed in every frame, let the policy merge its
// state, carry wedges, attributes and skin weights over, and collapse. Returns the number of
// faces removed; leaves the removed point's former edges in old_edges_ (greedy order only).
int32_t CollapseEngine::collapse(CollapsePolicy& policy, const Candidate& candidate, TriMesh::HalfedgeHandle halfedge,
                                 const Workspace& workspace, EngineRecord& record) {
  record.removed.push_back(prepared_.point_source[candidate.removed]);
  record.kept.push_back(prepared_.point_source[candidate.kept]);
  record.cost.push_back(candidate.cost);
  record.error.push_back(candidate.error);
  float* const kept_positions = &positions_[static_cast<size_t>(candidate.kept) * frame_count_ * 3];
  for (size_t frame = 0; frame < frame_count_; ++frame)
    for (int axis = 0; axis < 3; ++axis)
      kept_positions[frame * 3 + axis] = static_cast<float>(workspace.placed[frame][axis]);
  if (options_.record_positions)
    record.positions.insert(record.positions.end(), kept_positions, kept_positions + frame_count_ * 3);
  policy.merge(candidate);
  const auto t = static_cast<float>(candidate.t);
  const size_t attribute_count = data_.attribute_count;
  for (const auto& [from, to] : workspace.wedge_moves)
    for (size_t a = 0; a < attribute_count; ++a) {
      float& kept = attributes_[static_cast<size_t>(to) * attribute_count + a];
      kept += t * (attributes_[static_cast<size_t>(from) * attribute_count + a] - kept);
    }
  const size_t width = data_.position_attribute_count;
  for (size_t b = 0; b < width; ++b) {
    float& kept = position_attributes_[static_cast<size_t>(candidate.kept) * width + b];
    kept += t * (position_attributes_[static_cast<size_t>(candidate.removed) * width + b] - kept);
  }
  if (!skin_joints_.empty()) {
    const size_t k = data_.influence_count;
    const size_t kept = static_cast<size_t>(candidate.kept) * k, removed = static_cast<size_t>(candidate.removed) * k;
    merge_skin_weights(&skin_joints_[kept], &skin_weights_[kept], &skin_joints_[removed], &skin_weights_[removed], k,
                       candidate.t);
  }
  merged_into_[candidate.removed] = candidate.kept;
  if (!ranking_cache_.changed.empty()) ranking_cache_.changed[candidate.kept] = ranking_cache_.changed[candidate.removed] = 1;
  for (const auto& [from, to] : workspace.wedge_moves) wedge_merged_into_[from] = to;

  // Corners of the removed point now belong to the kept point, with the mapped wedge.
  const auto removed = connectivity_.vertex_handle(candidate.removed);
  for (const auto face : connectivity_.vf_range(removed)) {
    const size_t base = 3 * static_cast<size_t>(face.idx());
    for (size_t c = 0; c < 3; ++c) {
      if (corner_points_[base + c] != candidate.removed) continue;
      corner_points_[base + c] = candidate.kept;
      for (const auto& [from, to] : workspace.wedge_moves)
        if (corner_wedges_[base + c] == from) corner_wedges_[base + c] = to;
    }
  }
  // Connectivity: the edges of the removed point either move to the kept one or vanish (the
  // greedy loop takes the vanished ones out of its heap).
  old_edges_.clear();
  if (!options_.collapse_passes)
    for (const auto edge : connectivity_.ve_range(removed)) old_edges_.push_back(edge.idx());
  // Valences (the link condition holds): the points facing the edge lose one neighbour, the
  // kept point gains the removed point's neighbours but the shared ones and the two themselves.
  int32_t faces_removed = 0;
  for (const auto side : {halfedge, connectivity_.opposite_halfedge_handle(halfedge)}) {
    if (connectivity_.is_boundary(side)) continue;
    --valence_[connectivity_.to_vertex_handle(connectivity_.next_halfedge_handle(side)).idx()];
    ++faces_removed;
  }
  valence_[candidate.kept] += valence_[candidate.removed] - 2 - faces_removed;
  if (point_wedge_[candidate.removed] < 0) point_wedge_[candidate.kept] = -1;
  if (!collapse_away_from_borders(connectivity_, halfedge)) connectivity_.collapse(halfedge);
  return faces_removed;
}

// The halfedge from the removed point to the kept one (OpenMesh keeps the "to" vertex).
CollapseEngine::TriMesh::HalfedgeHandle CollapseEngine::removed_to_kept(const Candidate& candidate,
                                                                        int32_t edge) const {
  auto halfedge = connectivity_.halfedge_handle(connectivity_.edge_handle(edge), 0);
  if (connectivity_.from_vertex_handle(halfedge).idx() != candidate.removed)
    halfedge = connectivity_.opposite_halfedge_handle(halfedge);
  return halfedge;
}

// Re-evaluates the edges at `vertex`: all of them when its state changed, otherwise only the
// parked ones (their cost is unchanged, but their legality may have changed).
void CollapseEngine::rekey_around(CollapsePolicy& policy, TriMesh::VertexHandle vertex, bool all_edges) {
  if (!all_edges && !may_have_parked_[vertex.idx()]) return;
  may_have_parked_[vertex.idx()] = 0;
  for (const auto edge : connectivity_.ve_range(vertex)) {
    const int32_t e = edge.idx();
    if (!all_edges && !parked_[e]) continue;
    parked_[e] = 0;
    if (locked(edge.v0().idx()) && locked(edge.v1().idx())) continue;  // can never collapse
    heap_.set(e, evaluate(policy, e).cost);
  }
}

void CollapseEngine::park(int32_t edge) {
  heap_.remove(edge);
  parked_[edge] = 1;
  const auto handle = connectivity_.edge_handle(edge);
  may_have_parked_[connectivity_.to_vertex_handle(connectivity_.halfedge_handle(handle, 0)).idx()] = 1;
  may_have_parked_[connectivity_.to_vertex_handle(connectivity_.halfedge_handle(handle, 1)).idx()] = 1;
}

EngineLevel CollapseEngine::snapshot(size_t target, bool reached) {
  const PhaseTimer timer(timings_.levels);
  EngineLevel level;
  level.target_face_count = target;
  level.reached = reached;
  level.stopped_by_max_error = !reached && stopped_by_max_error_;
  level.error = error_so_far_;
  level.collapse_count = collapse_count_;
  const size_t vertex_count = mesh_.vertex_count;
  // Output vertices: the wedges that surviving corners use, in input order, each at the point
  // of a corner that uses it.
  std::vector<int32_t> wedge_point(vertex_count, -1);
  std::vector<int32_t> live_faces;
  for (const auto face : connectivity_.faces()) {
    if (connectivity_.status(face).deleted()) continue;
    live_faces.push_back(face.idx());
    const size_t base = 3 * static_cast<size_t>(face.idx());
    for (size_t c = 0; c < 3; ++c) wedge_point[corner_wedges_[base + c]] = corner_points_[base + c];
  }
  std::vector<int32_t> new_index(vertex_count, -1);
  std::vector<int32_t> point_vertex(point_count_, -1);  // the first output vertex of each point
  for (size_t v = 0; v < vertex_count; ++v) {
    if (wedge_point[v] < 0) continue;
    new_index[v] = static_cast<int32_t>(level.kept_vertices.size());
    if (point_vertex[wedge_point[v]] < 0) point_vertex[wedge_point[v]] = new_index[v];
    level.kept_vertices.push_back(static_cast<int32_t>(v));
  }
  // A wedge cut apart at a non-manifold spot stands at several (split) points, and wedge_point
  // keeps only one of them: the others get the lowest output vertex used at their corners, so
  // that a vertex merged into such a point maps to it (fuzz: tests/fuzz/crashes/simplify_animated).
  std::vector<int32_t> corner_vertex(point_count_, -1);
  for (int32_t f : live_faces)
    for (size_t c = 0; c < 3; ++c) {
      const int32_t point = corner_points_[3 * static_cast<size_t>(f) + c];
      const int32_t index = new_index[corner_wedges_[3 * static_cast<size_t>(f) + c]];
      if (point_vertex[point] < 0 && (corner_vertex[point] < 0 || index < corner_vertex[point])) corner_vertex[point] = index;
    }
  for (size_t p = 0; p < point_count_; ++p)
    if (point_vertex[p] < 0) point_vertex[p] = corner_vertex[p];
  for (int32_t f : live_faces) {
    level.face_sources.push_back(prepared_.face_sources[f]);
    for (size_t c = 0; c < 3; ++c) level.faces.push_back(new_index[corner_wedges_[3 * static_cast<size_t>(f) + c]]);
  }
  // A two-sided sheet's faces come back in the reverse turn on the same vertices, after the
  // others; the target counts them too.
  if (!prepared_.mirror_sources.empty())
    for (int32_t f : live_faces) {
      const int32_t mirror = prepared_.mirror_sources[static_cast<size_t>(f)];
      if (mirror < 0) continue;
      level.face_sources.push_back(mirror);
      for (size_t c : {0, 2, 1}) level.faces.push_back(new_index[corner_wedges_[3 * static_cast<size_t>(f) + c]]);
      ++level.target_face_count;
    }
  // An input vertex maps to the output vertex of the wedge it merged into; when no surviving
  // corner uses that wedge, to an output vertex of the point it merged into.
  level.vertex_map.assign(vertex_count, -1);
  for (size_t v = 0; v < vertex_count; ++v) {
    int32_t wedge = prepared_.wedge_representative[v];
    if (wedge < 0) continue;
    while (wedge_merged_into_[wedge] != wedge) wedge = wedge_merged_into_[wedge];
    if (new_index[wedge] >= 0) {
      level.vertex_map[v] = new_index[wedge];
      continue;
    }
    int32_t point = prepared_.wedge_point[wedge];
    while (merged_into_[point] != point) point = merged_into_[point];
    level.vertex_map[v] = point_vertex[point];
  }
  // A vertex that only a two-sided sheet's mirrors use maps where its front counterpart does.
  for (size_t i = 0; i < prepared_.mirror_vertices.size(); i += 2) {
    const auto mirror = static_cast<size_t>(prepared_.mirror_vertices[i]);
    const auto front = static_cast<size_t>(prepared_.mirror_vertices[i + 1]);
    if (level.vertex_map[mirror] < 0) level.vertex_map[mirror] = level.vertex_map[front];
  }
  const size_t kept_count = level.kept_vertices.size();
  level.positions.resize(frame_count_ * kept_count * 3);
  for (size_t i = 0; i < kept_count; ++i) {
    const float* source = &positions_[static_cast<size_t>(wedge_point[level.kept_vertices[i]]) * frame_count_ * 3];
    for (size_t frame = 0; frame < frame_count_; ++frame)
      std::copy_n(source + frame * 3, 3, &level.positions[(frame * kept_count + i) * 3]);
  }
  auto gather = [&](const auto& source, size_t width, auto& destination, bool by_point) {
    destination.resize(kept_count * width);
    // data() rather than &v[0]: an absent attribute set is an empty vector, and indexing it is UB.
    for (size_t i = 0; i < kept_count; ++i) {
      const int32_t row = by_point ? wedge_point[level.kept_vertices[i]] : level.kept_vertices[i];
      std::copy_n(source.data() + static_cast<size_t>(row) * width, width, destination.data() + i * width);
    }
  };
  gather(attributes_, data_.attribute_count, level.attributes, false);
  gather(position_attributes_, data_.position_attribute_count, level.position_attributes, true);
  if (!skin_joints_.empty()) {
    gather(skin_joints_, data_.influence_count, level.skin_joints, true);
    gather(skin_weights_, data_.influence_count, level.skin_weights, true);
  }
  return level;
}

// Guarded points stay in place until nothing else can collapse; then they are released, and
// their edges (including those between two guarded points) enter the heap. Returns whether
// that put anything in the heap.
bool CollapseEngine::release_guards(CollapsePolicy& policy) {
  if (released_) return false;
  released_ = true;
  if (in_passes_) {  // the next pass evaluates every edge, none from the last ranking (locked() changed)
    ranking_cache_.valid = false;
    return std::find(locked_.begin(), locked_.end(), kGuarded) != locked_.end();
  }
  for (size_t p = 0; p < point_count_; ++p) {
    if (locked_[p] != kGuarded) continue;
    const auto vertex = connectivity_.vertex_handle(static_cast<int>(p));
    if (!connectivity_.status(vertex).deleted()) rekey_around(policy, vertex, true);
  }
  return !heap_.empty();
}

void CollapseEngine::take_reached_levels(const std::vector<size_t>& targets, std::vector<EngineLevel>& levels) {
  for (; next_level_ < targets.size() && face_count_ <= targets[next_level_]; ++next_level_)
    levels.push_back(snapshot(targets[next_level_], true));
}

void CollapseEngine::run(CollapsePolicy& policy, const std::vector<size_t>& targets, std::vector<EngineLevel>& levels,
                         EngineRecord& record) {
  double seconds = 0.0;
  {
    const PhaseTimer timer(seconds);
    run_collapses(policy, targets, levels, record);
  }
  timings_.collapsing = seconds - timings_.ranking - timings_.choosing - timings_.levels;
}

void CollapseEngine::run_collapses(CollapsePolicy& policy, const std::vector<size_t>& targets,
                                   std::vector<EngineLevel>& levels, EngineRecord& record) {
  planned_ = face_count_ > targets.back() ? (face_count_ - targets.back() + 1) / 2 : 0;
  // A long clip's record holds every collapse's position in every frame: reserved (with room for
  // border collapses, which remove one face) so that growing does not copy gigabytes.
  const size_t expected = std::min(point_count_, planned_ + planned_ / 8 + 16);
  if (options_.record_positions) record.positions.reserve(expected * frame_count_ * 3);
  next_level_ = 0;
  take_reached_levels(targets, levels);
  if (options_.progress) options_.progress(0, planned_);
  if (options_.collapse_passes && connectivity_.n_edges() > options_.passes_above_edges) {
    run_passes(policy, targets, levels, record);
  } else {
    std::vector<RankedEdge> ranked;
    rank_collapsible_edges(policy, ranked);
    run_greedy(policy, ranked, targets, levels, record);
  }
  for (; next_level_ < targets.size(); ++next_level_) levels.push_back(snapshot(targets[next_level_], false));
  if (options_.progress) options_.progress(collapse_count_, planned_);
}

// Steps 7-12 in one global greedy order: an indexed heap of every edge, re-keyed around each
// collapse.
void CollapseEngine::run_greedy(CollapsePolicy& policy, const std::vector<RankedEdge>& ranked,
                                const std::vector<size_t>& targets, std::vector<EngineLevel>& levels,
                                EngineRecord& record) {
  // Step 7: every collapsible edge (`ranked`, rank_collapsible_edges) into the heap.
  const size_t edge_count = connectivity_.n_edges();
  heap_ = IndexedMinHeap(edge_count);
  parked_.assign(edge_count, 0);
  may_have_parked_.assign(point_count_, 0);
  std::vector<int32_t> ids(ranked.size());
  std::vector<double> keys(ranked.size());
  for (size_t i = 0; i < ranked.size(); ++i) ids[i] = ranked[i].edge, keys[i] = ranked[i].cost;
  heap_.assign(ids, keys);

  // Steps 8-12, taking a level each time the face count reaches a target.
  while (next_level_ < targets.size() && (!heap_.empty() || release_guards(policy))) {
    const int32_t edge = heap_.top();
    const Candidate candidate = candidate_for(edge);
    const Attempt attempt = try_collapse(policy, candidate, edge, targets, levels, record);
    if (attempt == Attempt::over_max_error) {
      stopped_by_max_error_ = true;
      break;
    }
    if (attempt == Attempt::illegal) {
      park(edge);
      continue;
    }
    for (int32_t old_edge : old_edges_)
      if (connectivity_.status(connectivity_.edge_handle(old_edge)).deleted()) heap_.remove(old_edge);
    // Step 10: the costs of the edges at the kept point changed; the legality of edges one ring
    // further may have changed, so parked edges there are tried again.
    const auto kept = connectivity_.vertex_handle(candidate.kept);
    rekey_around(policy, kept, true);
    for (const auto neighbour : connectivity_.vv_range(kept)) rekey_around(policy, neighbour, false);
  }
}

// Steps 8-9 for one candidate (kept and removed set) on `worker`: test the connectivity, evaluate
// the candidate again for its placement, test Eq. 7 and max_error, collapse into `record`. Leaves
// the collapse's values in `candidate`; the caller counts the collapse and its removed faces.
// The connectivity comes first as it needs no placement: in the greedy order most attempts are
// illegal (an edge parked as illegal is keyed again whenever its neighbourhood changes), and
// nearly all of those fail there.
CollapseEngine::Attempt CollapseEngine::attempt_collapse(CollapsePolicy& policy, Candidate& candidate, int32_t edge,
                                                         size_t worker, EngineRecord& record,
                                                         int32_t& faces_removed) {
  Workspace& workspace = workspaces_[worker];
  const auto halfedge = removed_to_kept(candidate, edge);
  if (!is_legal_connectivity(candidate, halfedge, workspace)) return Attempt::illegal;
  policy.evaluate_concurrently(candidate, worker);
  policy.place_concurrently(candidate, workspace.placed, worker);
  if (!keeps_orientation(candidate, workspace)) return Attempt::illegal;
  if (candidate.error > options_.max_error) return Attempt::over_max_error;
  faces_removed = collapse(policy, candidate, halfedge, workspace, record);
  return Attempt::collapsed;
}

// attempt_collapse on the engine's own thread, counted; takes the levels reached.
CollapseEngine::Attempt CollapseEngine::try_collapse(CollapsePolicy& policy, Candidate candidate, int32_t edge,
                                                     const std::vector<size_t>& targets,
                                                     std::vector<EngineLevel>& levels, EngineRecord& record) {
  int32_t faces_removed = 0;
  const Attempt attempt = attempt_collapse(policy, candidate, edge, 0, record, faces_removed);
  if (attempt != Attempt::collapsed) return attempt;
  error_so_far_ = std::max(error_so_far_, candidate.error);
  face_count_ -= static_cast<size_t>(faces_removed);
  ++collapse_count_;
  take_reached_levels(targets, levels);
  if (options_.progress && collapse_count_ % 4096 == 0) options_.progress(collapse_count_, planned_);
  return Attempt::collapsed;
}

// Every live edge that can collapse, with its cost, in edge order. The items are split in
// contiguous ranges over up to the policy's concurrency() threads (each candidate's values do
// not depend on the thread that computed them), each writing its part of `ranked` from the
// start of its range; the parts are then moved together. The items are the edges, or with a
// valid ranking_cache_ the entries of the last ranking (`ranked` itself, compacted in place: an
// entry is written at or before where it was read), of which only those at changed points are
// evaluated again: a pass deletes a fraction of the edges, and visiting all of them cost the
// later passes more than their evaluations.
void CollapseEngine::rank_collapsible_edges(CollapsePolicy& policy, std::vector<RankedEdge>& ranked) {
  const PhaseTimer timer(timings_.ranking);
  constexpr size_t kMinimumChunk = 8192;
  RankingCache& cache = ranking_cache_;
  const bool from_last = cache.valid && options_.rank_from_last;
  const size_t item_count = from_last ? ranked.size() : connectivity_.n_edges();
  const size_t workers = std::min({policy.concurrency(), size_t{thread_limit()}, std::max<size_t>(item_count / kMinimumChunk, 1)});
  if (!from_last) ranked.resize(item_count);
  auto rank_edge = [&](int32_t edge, size_t worker, size_t& out) {
    if (connectivity_.status(connectivity_.edge_handle(edge)).deleted()) return;
    Candidate candidate = candidate_for(edge);
    if (locked(candidate.kept) && locked(candidate.removed)) return;  // cannot collapse (yet)
    policy.evaluate_concurrently(candidate, worker);
    ranked[out++] = {candidate.cost, candidate.error, edge, candidate.kept, candidate.removed};
  };
  std::vector<size_t> ends(workers);
  run_in_ranges(item_count, workers, [&](size_t begin, size_t end, size_t worker) {
    size_t out = begin;
    if (!from_last) {
      for (size_t e = begin; e < end; ++e) rank_edge(static_cast<int32_t>(e), worker, out);
    } else {
      for (size_t i = begin; i < end; ++i) {
        const RankedEdge entry = ranked[i];
        if (cache.changed[entry.kept] || cache.changed[entry.removed]) rank_edge(entry.edge, worker, out);
        else ranked[out++] = entry;
      }
    }
    ends[worker] = out;
  });
  if (!cache.changed.empty()) {
    std::fill(cache.changed.begin(), cache.changed.end(), 0);
    cache.valid = true;
  }
  size_t size = ends[0];
  for (size_t worker = 1; worker < workers; ++worker) {
    const auto begin = ranked.begin() + static_cast<std::ptrdiff_t>(item_count * worker / workers);
    size = static_cast<size_t>(std::copy(begin, ranked.begin() + static_cast<std::ptrdiff_t>(ends[worker]),
                                         ranked.begin() + static_cast<std::ptrdiff_t>(size)) -
                               ranked.begin());
  }
  ranked.resize(size);
}

namespace {

void append(EngineRecord& to, const EngineRecord& from) {
  auto append_vector = [](auto& destination, const auto& source) {
    destination.insert(destination.end(), source.begin(), source.end());
  };
  append_vector(to.removed, from.removed);
  append_vector(to.kept, from.kept);
  append_vector(to.positions, from.positions);
  append_vector(to.cost, from.cost);
  append_vector(to.error, from.error);
}

}  // namespace

// half_: the side of a plane each point is on, the plane across the axis along which the chosen
// collapses' kept points spread most, through their median (each worker gets half of them).
void CollapseEngine::split_points_in_halves(const std::vector<RankedEdge>& chosen) {
  const size_t stride = frame_count_ * 3;  // a point's frame 0 in positions_
  Eigen::Array3f low = Eigen::Array3f::Constant(std::numeric_limits<float>::infinity()), high = -low;
  for (const RankedEdge& entry : chosen) {
    const Eigen::Map<const Eigen::Array3f> position(&positions_[static_cast<size_t>(entry.kept) * stride]);
    low = low.min(position);
    high = high.max(position);
  }
  Eigen::Index axis = 0;
  (high - low).maxCoeff(&axis);
  std::vector<float> coordinates(chosen.size());
  for (size_t i = 0; i < chosen.size(); ++i)
    coordinates[i] = positions_[static_cast<size_t>(chosen[i].kept) * stride + static_cast<size_t>(axis)];
  const auto middle = coordinates.begin() + static_cast<std::ptrdiff_t>(coordinates.size() / 2);
  std::nth_element(coordinates.begin(), middle, coordinates.end());
  const float median = *middle;
  half_.resize(point_count_);
  for (size_t p = 0; p < point_count_; ++p) half_[p] = positions_[p * stride + static_cast<size_t>(axis)] < median ? 0 : 1;
}

// Whether collapsing `entry` reads and writes only points of `half`: OpenMesh's collapse and
// is_collapse_ok touch the two endpoints, the points around them and the elements between those;
// the engine and the policy likewise. A split point's wedge stands at other points too.
bool CollapseEngine::stays_in_half(const RankedEdge& entry, uint8_t half) const {
  for (const int32_t point : {entry.kept, entry.removed}) {
    if (half_[point] != half || prepared_.point_split[point]) return false;
    for (const auto neighbour : connectivity_.vv_range(connectivity_.vertex_handle(point)))
      if (half_[neighbour.idx()] != half) return false;
  }
  return true;
}

// A pass's chosen collapses on two workers, one per half of the mesh (split_points_in_halves),
// each in edge order; those near the other half are left in `deferred` (edge order) for the
// engine's thread. Both halves touch disjoint points, faces and edges, so each worker's
// collapses are those it would make alone, in any interleaving: the levels do not depend on
// timing. The records follow one another, the first half's first: a valid order of the same
// collapses.
CollapseEngine::Performed CollapseEngine::perform_in_halves(CollapsePolicy& policy,
                                                            const std::vector<RankedEdge>& chosen,
                                                            const std::vector<size_t>& targets,
                                                            std::vector<EngineLevel>& levels, EngineRecord& record,
                                                            std::vector<RankedEdge>& deferred) {
  struct Half {
    EngineRecord record;
    std::vector<RankedEdge> deferred;
    size_t collapses = 0, illegal = 0, faces_removed = 0;
    double error = 0.0;
  };
  std::array<Half, 2> halves;
  split_points_in_halves(chosen);
  run_in_ranges(2, 2, [&](size_t, size_t, size_t worker) {
    Half& half = halves[worker];
    for (const RankedEdge& entry : chosen) {
      if (half_[entry.kept] != worker) continue;
      if (!stays_in_half(entry, static_cast<uint8_t>(worker))) {
        half.deferred.push_back(entry);
        continue;
      }
      Candidate candidate;
      candidate.kept = entry.kept;
      candidate.removed = entry.removed;
      int32_t faces_removed = 0;
      const Attempt attempt = attempt_collapse(policy, candidate, entry.edge, worker, half.record, faces_removed);
      if (attempt == Attempt::illegal) ++half.illegal;
      if (attempt != Attempt::collapsed) continue;
      ++half.collapses;
      half.faces_removed += static_cast<size_t>(faces_removed);
      half.error = std::max(half.error, candidate.error);
    }
  });
  Performed performed;
  for (const Half& half : halves) {
    append(record, half.record);
    collapse_count_ += half.collapses;
    face_count_ -= half.faces_removed;
    error_so_far_ = std::max(error_so_far_, half.error);
    performed.collapses += half.collapses;
    performed.illegal += half.illegal;
  }
  deferred.clear();
  std::merge(halves[0].deferred.begin(), halves[0].deferred.end(), halves[1].deferred.begin(),
             halves[1].deferred.end(), std::back_inserter(deferred),
             [](const RankedEdge& a, const RankedEdge& b) { return a.edge < b.edge; });
  take_reached_levels(targets, levels);
  if (options_.progress) options_.progress(collapse_count_, planned_);
  return performed;
}

// Steps 7-12 as meshoptimizer's collapse passes (simplifier.cpp: pickEdgeCollapses,
// sortEdgeCollapses, performEdgeCollapses): every live edge is evaluated and the candidates
// ranked by (cost, edge). A pass chooses its collapses in that order, each point at most once
// (so every chosen cost stays exact: it depends only on its two points), as if each removed two
// faces, until the next level's face count, or until the cost exceeds pass_cost_growth times
// the cost of the candidate the pass would reach if every collapse succeeded (the order stays
// close to the greedy one). The chosen collapses are then performed in edge order, whose
// neighbours share OpenMesh's records in memory (the cost order scatters them: the 1M-triangle
// sphere's collapses took 2.5 s that way), legality checked against the current mesh, on two
// workers where the policy allows (perform_in_halves). Where illegal or boundary collapses
// leave the pass short of its goal, it goes on down the ranking one collapse at a time.
void CollapseEngine::run_passes(CollapsePolicy& policy, const std::vector<size_t>& targets,
                                std::vector<EngineLevel>& levels, EngineRecord& record) {
  constexpr size_t kMinimumHalves = 2048;  // fewer chosen collapses go one by one
  std::vector<RankedEdge> ranked, chosen, deferred;
  CostOrder cost_order;  // ranked comes in edge order, so its (cost, index) order is (cost, edge)
  // The pass's chosen candidates, one bit per place in ranked: read in order of place, which is
  // edge order, and small enough to stay in cache while the choice sets bits at random.
  std::vector<uint64_t> chosen_places;
  std::vector<uint8_t> touched(point_count_, 0);
  in_passes_ = true;
  ranking_cache_.changed.assign(point_count_, 0);
  while (next_level_ < targets.size()) {
    // Step 7: every collapsible edge, evaluated.
    rank_collapsible_edges(policy, ranked);
    if (ranked.size() <= options_.greedy_tail_edges) {
      // The last few edges in one greedy order: re-keying them costs little, and on small
      // meshes and coarse levels the order matters most.
      in_passes_ = false;
      ranking_cache_ = {};
      run_greedy(policy, ranked, targets, levels, record);
      return;
    }
    const size_t face_goal = face_count_ - targets[next_level_];
    size_t edge_goal = face_goal / 2;  // an illegal collapse does not count towards the goal
    auto within_cost_goal = [&](double cost, size_t removed_faces) {
      return removed_faces <= face_goal / 6 || edge_goal >= cost_order.size() ||
             cost <= options_.pass_cost_growth * ranked[cost_order[edge_goal]].cost;
    };

    // Steps 8-12: choose, then perform in edge order.
    size_t next = 0;
    bool over_max_error = false;  // the pass stops at the first candidate whose error exceeds max_error
    {
      const PhaseTimer timer(timings_.choosing);
      cost_order.sort(ranked);
      std::fill(touched.begin(), touched.end(), 0);
      chosen_places.assign((ranked.size() + 63) / 64, 0);
      for (size_t planned_faces = 0; next < cost_order.size() && planned_faces < face_goal; ++next) {
        // The candidates scatter over `ranked`: a load ahead overlaps its cache miss with the
        // choices before it.
        constexpr size_t kLookahead = 16;
        if (const int64_t ahead = cost_order.ordered_index(next + kLookahead); ahead >= 0)
          prefetch_for_read(&ranked[static_cast<size_t>(ahead)]);
        const uint32_t index = cost_order[next];
        const RankedEdge& entry = ranked[index];
        if (!within_cost_goal(entry.cost, planned_faces)) break;
        if (touched[entry.kept] || touched[entry.removed]) continue;
        over_max_error = entry.error > options_.max_error;
        if (over_max_error) break;
        touched[entry.kept] = touched[entry.removed] = 1;
        chosen_places[index / 64] |= uint64_t{1} << (index % 64);
        planned_faces += 2;
      }
      chosen.clear();
      for (size_t word = 0; word < chosen_places.size(); ++word)
        for (uint64_t bits = chosen_places[word]; bits != 0; bits &= bits - 1)
          chosen.push_back(ranked[64 * word + static_cast<size_t>(lowest_set_bit(bits))]);
    }
    const size_t faces_before = face_count_;
    size_t pass_collapses = 0;
    auto try_entry = [&](const RankedEdge& entry) {
      Candidate candidate;
      candidate.kept = entry.kept;
      candidate.removed = entry.removed;
      const Attempt attempt = try_collapse(policy, candidate, entry.edge, targets, levels, record);
      if (attempt == Attempt::illegal) ++edge_goal;
      if (attempt == Attempt::collapsed) ++pass_collapses;
      return attempt == Attempt::collapsed;
    };
    const std::vector<RankedEdge>* one_by_one = &chosen;
    if (chosen.size() >= kMinimumHalves && policy.concurrency() >= 2 && thread_limit() >= 2) {
      const Performed performed = perform_in_halves(policy, chosen, targets, levels, record, deferred);
      pass_collapses += performed.collapses;
      edge_goal += performed.illegal;
      one_by_one = &deferred;
    }
    for (const RankedEdge& entry : *one_by_one) try_entry(entry);
    for (; !over_max_error && next < cost_order.size(); ++next) {
      const size_t removed_faces = faces_before - face_count_;
      if (removed_faces >= face_goal) break;
      const RankedEdge& entry = ranked[cost_order[next]];
      if (!within_cost_goal(entry.cost, removed_faces)) break;
      if (touched[entry.kept] || touched[entry.removed]) continue;
      over_max_error = entry.error > options_.max_error;
      if (!over_max_error && try_entry(entry)) touched[entry.kept] = touched[entry.removed] = 1;
    }
    // A pass without a collapse went through every candidate: nothing legal remains (or the
    // cheapest legal collapse exceeds max_error), unless guarded points can be released.
    if (pass_collapses == 0 && (over_max_error || !release_guards(policy))) {
      stopped_by_max_error_ = over_max_error;
      break;
    }
  }
  ranking_cache_ = {};
}

}  // namespace animlod::detail
