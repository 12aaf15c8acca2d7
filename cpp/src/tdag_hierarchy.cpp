// The TDAG's vertex hierarchy and dependencies from a collapse order (Shamir and Pascucci 2001,
// Sections 2 and 4; the dependency DAG of [4, 13]: a node depends on the decimations that last
// touched the faces around it).
#include "tdag_hierarchy.hpp"

#include <algorithm>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "edge_table.hpp"

namespace animlod::detail {

namespace {

void erase_value(std::vector<int32_t>& list, int32_t value) {
  auto it = std::find(list.begin(), list.end(), value);
  if (it == list.end()) return;
  *it = list.back();
  list.pop_back();
}

// Faces with both vertices as corners (the faces on their edge).
void shared_faces(const std::vector<int32_t>& around, const std::vector<int32_t>& corners, int32_t other,
                  std::vector<int32_t>& out) {
  out.clear();
  for (int32_t f : around)
    for (size_t k = 0; k < 3; ++k)
      if (corners[3 * static_cast<size_t>(f) + k] == other) out.push_back(f);
}

}  // namespace

Status record_hierarchy(const int32_t* faces, size_t face_count, size_t vertex_count,
                        const std::vector<VertexCollapse>& collapses,
                        const std::vector<std::vector<int32_t>>* twins, CollapseTable& table, FrameHierarchy& out) {
  out = FrameHierarchy{};
  out.dep_offsets.push_back(0);
  std::vector<int32_t> corners(faces, faces + 3 * face_count);  // current vertex of every corner
  std::vector<std::vector<int32_t>> around(vertex_count);      // live faces around every vertex
  for (size_t f = 0; f < face_count; ++f)
    for (size_t k = 0; k < 3; ++k) around[static_cast<size_t>(faces[3 * f + k])].push_back(static_cast<int32_t>(f));
  std::vector<int32_t> node_of(vertex_count);  // hierarchy node each live vertex stands for
  for (size_t v = 0; v < vertex_count; ++v) node_of[v] = static_cast<int32_t>(v);
  std::vector<uint8_t> removed_already(vertex_count, 0);
  std::vector<int32_t> last_modifier(face_count, -1);
  std::vector<int32_t> edge_faces, deps;

  for (size_t i = 0; i < collapses.size(); ++i) {
    VertexCollapse c = collapses[i];
    const auto name = [&] {
      return "collapse " + std::to_string(i) + " (vertex " + std::to_string(c.removed) + " into " +
             std::to_string(c.kept) + ")";
    };
    if (c.removed < 0 || c.kept < 0 || static_cast<size_t>(c.removed) >= vertex_count ||
        static_cast<size_t>(c.kept) >= vertex_count || c.removed == c.kept)
      return Status::error(name() + ": vertex index outside [0, " + std::to_string(vertex_count) + ") or repeated");
    const auto r = static_cast<size_t>(c.removed);
    shared_faces(around[r], corners, c.kept, edge_faces);
    if (edge_faces.empty() && twins)
      for (int32_t twin : (*twins)[static_cast<size_t>(c.kept)]) {
        shared_faces(around[r], corners, twin, edge_faces);
        if (!edge_faces.empty()) {
          c.kept = twin;
          break;
        }
      }
    const auto k = static_cast<size_t>(c.kept);
    if (removed_already[r] || removed_already[k]) return Status::error(name() + ": an endpoint was removed before");
    if (edge_faces.empty() || edge_faces.size() > 2) return Status::error(name() + ": the endpoints share no edge");

    // Dependencies: the collapses that last changed a face around either endpoint.
    deps.clear();
    for (size_t endpoint : {r, k})
      for (int32_t f : around[endpoint])
        if (last_modifier[static_cast<size_t>(f)] >= 0) deps.push_back(last_modifier[static_cast<size_t>(f)]);
    std::sort(deps.begin(), deps.end());
    deps.erase(std::unique(deps.begin(), deps.end()), deps.end());
    const int32_t node = c.from_removed ? table.add(node_of[r], node_of[k]) : table.add(node_of[k], node_of[r]);
    auto& killed = table.killed[static_cast<size_t>(node - table.vertex_count())];
    killed = {edge_faces[0], edge_faces.size() > 1 ? edge_faces[1] : -1};
    out.nodes.push_back(node);
    out.dep_nodes.insert(out.dep_nodes.end(), deps.begin(), deps.end());
    out.dep_offsets.push_back(static_cast<int32_t>(out.dep_nodes.size()));

    // The faces on the edge go; the removed vertex's other faces move to the kept vertex.
    for (int32_t f : edge_faces)
      for (size_t corner = 0; corner < 3; ++corner)
        erase_value(around[static_cast<size_t>(corners[3 * static_cast<size_t>(f) + corner])], f);
    for (int32_t f : around[r]) {
      for (size_t corner = 0; corner < 3; ++corner)
        if (corners[3 * static_cast<size_t>(f) + corner] == c.removed) corners[3 * static_cast<size_t>(f) + corner] = c.kept;
      around[k].push_back(f);
    }
    around[r].clear();
    removed_already[r] = 1;
    node_of[k] = node;
    for (int32_t f : around[k]) last_modifier[static_cast<size_t>(f)] = node;
  }
  return Status::success();
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
