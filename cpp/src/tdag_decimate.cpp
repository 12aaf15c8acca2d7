// The TDAG's collapse loop (Shamir and Pascucci 2001, Sections 2 and 4): edge contraction
// with the quadric error metric [5] as the decimation primitive, here as half-edge collapses
// (the removed vertex merges into the kept one, which keeps its position), so that every node
// of the vertex hierarchy has the position of one input vertex in every frame.
//
// Besides the hierarchy, the loop records the dependencies of every collapse: the collapses
// that last changed a face around either endpoint. A set of collapses closed under those
// dependencies, applied in order to the input, meets at every collapse exactly the faces
// around its edge that the full order met, so every such set (a cut of the DAG) is a valid
// manifold mesh; and the faces a collapse removes are those with one corner in each child's
// cluster, whatever else is applied.
#include "tdag_decimate.hpp"

#include <algorithm>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <OpenMesh/Core/Mesh/TriConnectivity.hh>

#include "edge_table.hpp"
#include "indexed_heap.hpp"

namespace animlod::detail {

namespace {

using TriMesh = OpenMesh::TriConnectivity;

class FrameDecimator {
 public:
  FrameDecimator(const DecimationInput& input, CollapseTable& table, FrameHierarchy& out)
      : in_(input), table_(table), out_(out) {}

  Status run();

 private:
  Eigen::Vector3d position(int32_t vertex) const {
    const float* p = in_.positions + 3 * static_cast<size_t>(vertex);
    return {p[0], p[1], p[2]};
  }
  double cost(TriMesh::HalfedgeHandle h) const;
  double priority(TriMesh::HalfedgeHandle h) const;
  bool is_legal(TriMesh::HalfedgeHandle h, bool geometric);
  bool keeps_orientation(TriMesh::HalfedgeHandle h);
  void collapse(TriMesh::HalfedgeHandle h);
  void rekey_around(TriMesh::VertexHandle vertex, bool all_halfedges);
  void park(int32_t halfedge);

  const DecimationInput& in_;
  CollapseTable& table_;
  FrameHierarchy& out_;
  TriMesh mesh_;
  std::vector<Quadric> quadrics_;       // (V,) merged into the kept vertex
  std::vector<int32_t> node_of_;        // (V,) hierarchy node each live vertex stands for now
  std::vector<int32_t> last_modifier_;  // (M,) collapse node that last changed the face, -1: none
  std::vector<uint8_t> parked_;         // (2E,) popped while illegal
  std::vector<uint8_t> may_have_parked_;  // (V,)
  std::vector<int32_t> scratch_;
  IndexedMinHeap heap_{0};
  bool replaying_ = false;
};

double FrameDecimator::cost(TriMesh::HalfedgeHandle h) const {
  const int32_t removed = mesh_.from_vertex_handle(h).idx(), kept = mesh_.to_vertex_handle(h).idx();
  return (quadrics_[static_cast<size_t>(removed)] + quadrics_[static_cast<size_t>(kept)]).evaluate(position(kept));
}

// The quadric cost plus kLengthWeight times the squared edge length: quadric costs vanish on
// flat and cylindrical parts, where ties broken by index would grow one vertex's cluster along a
// line; the small length term takes the shorter edges first there, which keeps the hierarchy
// balanced and the displacement bounds small. The recorded cost (Figure 6) is the quadric's.
double FrameDecimator::priority(TriMesh::HalfedgeHandle h) const {
  constexpr double kLengthWeight = 1e-3;
  const int32_t removed = mesh_.from_vertex_handle(h).idx(), kept = mesh_.to_vertex_handle(h).idx();
  const double c = cost(h) + kLengthWeight * (position(removed) - position(kept)).squaredNorm();
  if (!in_.priority) return c;
  return in_.priority->priority(node_of_[static_cast<size_t>(kept)], node_of_[static_cast<size_t>(removed)], c);
}

// Faces around the removed vertex that survive move its corner onto the kept vertex; none may
// turn over or lose all its area in the decimated frame.
bool FrameDecimator::keeps_orientation(TriMesh::HalfedgeHandle h) {
  const auto removed = mesh_.from_vertex_handle(h);
  const int32_t kept = mesh_.to_vertex_handle(h).idx();
  const Eigen::Vector3d target = position(kept);
  for (const auto face : mesh_.vf_range(removed)) {
    Eigen::Vector3d before[3], after[3];
    int corner = 0;
    bool has_kept = false;
    for (const auto vertex : face.vertices()) {
      has_kept |= vertex.idx() == kept;
      before[corner] = position(vertex.idx());
      after[corner] = vertex == removed ? target : before[corner];
      ++corner;
    }
    if (has_kept) continue;  // one of the faces on the edge: removed
    const Eigen::Vector3d n_before = (before[1] - before[0]).cross(before[2] - before[0]);
    const Eigen::Vector3d n_after = (after[1] - after[0]).cross(after[2] - after[0]);
    if (n_before.squaredNorm() == 0.0) continue;  // no orientation to keep
    if (!(n_before.dot(n_after) > 0.0)) return false;
  }
  return true;
}

bool FrameDecimator::is_legal(TriMesh::HalfedgeHandle h, bool geometric) {
  if (!mesh_.is_collapse_ok(h)) return false;
  // A valence-3 interior vertex beside the edge would leave two faces on the same three
  // vertices (a tetrahedron folding flat); is_collapse_ok allows that.
  for (const auto side : {h, mesh_.opposite_halfedge_handle(h)}) {
    if (mesh_.is_boundary(side)) continue;
    const auto opposite = mesh_.to_vertex_handle(mesh_.next_halfedge_handle(side));
    if (!mesh_.is_boundary(opposite) && mesh_.valence(opposite) <= 3) return false;
  }
  return !geometric || !in_.check_inversion || keeps_orientation(h);
}

void FrameDecimator::collapse(TriMesh::HalfedgeHandle h) {
  const auto removed = mesh_.from_vertex_handle(h), kept = mesh_.to_vertex_handle(h);
  // Dependencies: the collapses that last changed a face around either endpoint.
  scratch_.clear();
  for (const auto vertex : {removed, kept})
    for (const auto face : mesh_.vf_range(vertex)) {
      const int32_t modifier = last_modifier_[static_cast<size_t>(face.idx())];
      if (modifier >= 0) scratch_.push_back(modifier);
    }
  std::sort(scratch_.begin(), scratch_.end());
  scratch_.erase(std::unique(scratch_.begin(), scratch_.end()), scratch_.end());
  std::array<int32_t, 2> killed{-1, -1};
  int k = 0;
  for (const auto side : {h, mesh_.opposite_halfedge_handle(h)})
    if (!mesh_.is_boundary(side)) killed[k++] = mesh_.face_handle(side).idx();
  const int32_t node = table_.add(node_of_[static_cast<size_t>(kept.idx())],
                                  node_of_[static_cast<size_t>(removed.idx())], killed);
  out_.nodes.push_back(node);
  out_.costs.push_back(cost(h));
  out_.dep_nodes.insert(out_.dep_nodes.end(), scratch_.begin(), scratch_.end());
  out_.dep_offsets.push_back(static_cast<int32_t>(out_.dep_nodes.size()));

  quadrics_[static_cast<size_t>(kept.idx())] += quadrics_[static_cast<size_t>(removed.idx())];
  std::vector<int32_t> old_edges;
  for (const auto edge : mesh_.ve_range(removed)) old_edges.push_back(edge.idx());
  mesh_.collapse(h);
  node_of_[static_cast<size_t>(kept.idx())] = node;
  for (const auto face : mesh_.vf_range(kept)) last_modifier_[static_cast<size_t>(face.idx())] = node;
  if (replaying_) return;
  for (int32_t edge : old_edges) {
    if (!mesh_.status(mesh_.edge_handle(edge)).deleted()) continue;
    heap_.remove(2 * edge);
    heap_.remove(2 * edge + 1);
  }
  // The endpoints' quadric and node changed: every halfedge at the kept vertex; legality may
  // have changed one ring further, so parked halfedges there are tried again.
  rekey_around(kept, true);
  for (const auto neighbour : mesh_.vv_range(kept)) rekey_around(neighbour, false);
}

void FrameDecimator::rekey_around(TriMesh::VertexHandle vertex, bool all_halfedges) {
  if (!all_halfedges && !may_have_parked_[static_cast<size_t>(vertex.idx())]) return;
  may_have_parked_[static_cast<size_t>(vertex.idx())] = 0;
  for (const auto outgoing : mesh_.voh_range(vertex)) {
    const TriMesh::HalfedgeHandle out_halfedge = outgoing;
    for (const TriMesh::HalfedgeHandle h : {out_halfedge, mesh_.opposite_halfedge_handle(out_halfedge)}) {
      const int32_t id = h.idx();
      if (!all_halfedges && !parked_[static_cast<size_t>(id)]) continue;
      parked_[static_cast<size_t>(id)] = 0;
      heap_.set(id, priority(h));
    }
  }
}

void FrameDecimator::park(int32_t halfedge) {
  heap_.remove(halfedge);
  parked_[static_cast<size_t>(halfedge)] = 1;
  const auto h = mesh_.halfedge_handle(halfedge);
  may_have_parked_[static_cast<size_t>(mesh_.from_vertex_handle(h).idx())] = 1;
  may_have_parked_[static_cast<size_t>(mesh_.to_vertex_handle(h).idx())] = 1;
}

Status FrameDecimator::run() {
  const size_t vertex_count = in_.vertex_count;
  mesh_.request_vertex_status();
  mesh_.request_edge_status();
  mesh_.request_face_status();
  std::vector<TriMesh::VertexHandle> handles(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) handles[v] = mesh_.new_vertex();
  for (size_t f = 0; f < in_.face_count; ++f) {
    const int32_t* v = in_.faces + 3 * f;
    if (!mesh_.add_face(handles[static_cast<size_t>(v[0])], handles[static_cast<size_t>(v[1])],
                        handles[static_cast<size_t>(v[2])]).is_valid())
      return Status::error("face " + std::to_string(f) + ": OpenMesh cannot add it to the halfedge mesh");
  }
  const std::vector<BoundarySide> boundary = in_.boundary_quadrics ? boundary_sides(in_.faces, in_.face_count)
                                                                   : std::vector<BoundarySide>{};
  vertex_quadrics(in_.positions, in_.faces, vertex_count, in_.face_count, in_.boundary_quadrics ? &boundary : nullptr,
                  quadrics_);
  node_of_.resize(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) node_of_[v] = static_cast<int32_t>(v);
  last_modifier_.assign(in_.face_count, -1);
  out_ = FrameHierarchy{};
  out_.dep_offsets.push_back(0);
  const size_t halfedge_count = 2 * mesh_.n_edges();
  heap_ = IndexedMinHeap(halfedge_count);
  parked_.assign(halfedge_count, 0);
  may_have_parked_.assign(vertex_count, 0);

  if (in_.replay_count > 0) {
    replaying_ = true;
    for (size_t i = 0; i < in_.replay_count; ++i) {
      const int32_t removed = in_.replay_removed[i], kept = in_.replay_kept[i];
      const auto name = [&] {
        return "collapse " + std::to_string(i) + " (vertex " + std::to_string(removed) + " into " +
               std::to_string(kept) + ")";
      };
      if (removed < 0 || kept < 0 || static_cast<size_t>(removed) >= vertex_count ||
          static_cast<size_t>(kept) >= vertex_count)
        return Status::error(name() + ": vertex index outside [0, " + std::to_string(vertex_count) + ")");
      const auto h = mesh_.find_halfedge(handles[static_cast<size_t>(removed)], handles[static_cast<size_t>(kept)]);
      if (!h.is_valid() || mesh_.status(mesh_.edge_handle(h)).deleted())
        return Status::error(name() + ": no such edge in the mesh reached by the collapses before it");
      if (!is_legal(h, false)) return Status::error(name() + ": not a legal collapse on the mesh reached");
      collapse(h);
    }
    return Status::success();
  }

  // Every halfedge into the heap, keyed by its priority.
  std::vector<int32_t> ids(halfedge_count);
  std::vector<double> keys(halfedge_count);
  for (size_t id = 0; id < halfedge_count; ++id) {
    ids[id] = static_cast<int32_t>(id);
    keys[id] = priority(mesh_.halfedge_handle(static_cast<int>(id)));
  }
  heap_.assign(ids, keys);
  while (!heap_.empty()) {
    const int32_t id = heap_.top();
    const auto h = mesh_.halfedge_handle(id);
    if (!is_legal(h, true)) {
      park(id);
      continue;
    }
    collapse(h);
  }
  return Status::success();
}

}  // namespace

Status decimate_frame(const DecimationInput& input, CollapseTable& table, FrameHierarchy& out) {
  FrameDecimator decimator(input, table, out);
  return decimator.run();
}

std::vector<BoundarySide> boundary_sides(const int32_t* faces, size_t face_count) {
  const EdgeTable edges = build_edge_table(faces, face_count);
  std::vector<BoundarySide> sides;
  for (size_t e = 0; e < edges.size(); ++e) {
    if (!edges.is_boundary(e)) continue;
    const int32_t face = edges.faces[e][0] >= 0 ? edges.faces[e][0] : edges.faces[e][1];
    const int32_t* v = faces + 3 * static_cast<size_t>(face);
    for (int corner = 0; corner < 3; ++corner) {
      const int32_t a = v[corner], b = v[(corner + 1) % 3];
      if (std::min(a, b) == edges.vertices[e][0] && std::max(a, b) == edges.vertices[e][1]) {
        sides.push_back({a, b, v[(corner + 2) % 3]});
        break;
      }
    }
  }
  return sides;
}

void vertex_quadrics(const float* positions, const int32_t* faces, size_t vertex_count, size_t face_count,
                     const std::vector<BoundarySide>* boundary, std::vector<Quadric>& out) {
  out.assign(vertex_count, Quadric{});
  auto point = [positions](int32_t v) {
    const float* p = positions + 3 * static_cast<size_t>(v);
    return Eigen::Vector3d(p[0], p[1], p[2]);
  };
  for (size_t f = 0; f < face_count; ++f) {
    const int32_t* v = faces + 3 * f;
    const Eigen::Vector3d p0 = point(v[0]), p1 = point(v[1]), p2 = point(v[2]);
    const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
    const double length = normal.norm();
    if (length == 0.0) continue;
    const Quadric plane = Quadric::plane(normal / length, p0, 1.0);
    for (int corner = 0; corner < 3; ++corner) out[static_cast<size_t>(v[corner])] += plane;
  }
  if (!boundary) return;
  for (const BoundarySide& side : *boundary) {
    const Eigen::Vector3d pa = point(side.a), pb = point(side.b), pc = point(side.c);
    const Eigen::Vector3d face_normal = (pb - pa).cross(pc - pa);
    const Eigen::Vector3d normal = (pb - pa).cross(face_normal);
    const double length = normal.norm();
    if (length == 0.0) continue;
    const Quadric plane = Quadric::plane(normal / length, pa, 1.0);
    out[static_cast<size_t>(side.a)] += plane;
    out[static_cast<size_t>(side.b)] += plane;
  }
}

}  // namespace animlod::detail
