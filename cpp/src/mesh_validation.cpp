// Input checks for animated meshes; every error names the offending element.
#include "animlod/mesh_validation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "edge_table.hpp"
#include "mesh_validation_detail.hpp"
#include "union_find.hpp"

namespace animlod {

namespace {

std::string face_text(const AnimatedMeshView& mesh, size_t f) {
  const int32_t* v = mesh.faces + 3 * f;
  return "face " + std::to_string(f) + " (" + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " +
         std::to_string(v[2]) + ")";
}

Status check_sizes_and_values(const AnimatedMeshView& mesh) {
  if (mesh.frame_count == 0) return Status::error("frames: the mesh has no frames");
  if (mesh.face_count == 0) return Status::error("faces: the mesh has no faces");
  // Vertices, faces and face corners (3 M) are numbered with int32 everywhere downstream.
  constexpr size_t kMaxIndex = std::numeric_limits<int32_t>::max();
  if (mesh.vertex_count > kMaxIndex)
    return Status::error("frames: " + std::to_string(mesh.vertex_count) + " vertices, more than int32 indices reach (" +
                         std::to_string(kMaxIndex) + ")");
  if (mesh.face_count > kMaxIndex / 3)
    return Status::error("faces: " + std::to_string(mesh.face_count) +
                         " faces, more than int32 corner indices reach (3 M <= " + std::to_string(kMaxIndex) + ")");
  const size_t value_count = mesh.frame_count * mesh.vertex_count * 3;
  for (size_t i = 0; i < value_count; ++i) {
    if (!std::isfinite(mesh.frames[i])) {
      const size_t per_frame = mesh.vertex_count * 3;
      return Status::error("frame " + std::to_string(i / per_frame) + ", vertex " +
                           std::to_string(i % per_frame / 3) + ": non-finite position");
    }
  }
  const auto vertex_count = static_cast<int64_t>(mesh.vertex_count);
  for (size_t f = 0; f < mesh.face_count; ++f) {
    const int32_t* v = mesh.faces + 3 * f;
    for (int k = 0; k < 3; ++k)
      if (v[k] < 0 || v[k] >= vertex_count)
        return Status::error(face_text(mesh, f) + ": vertex index " + std::to_string(v[k]) + " outside [0, " +
                             std::to_string(vertex_count) + ")");
  }
  return Status::success();
}

Status check_no_degenerate_faces(const AnimatedMeshView& mesh) {
  for (size_t f = 0; f < mesh.face_count; ++f) {
    const int32_t* v = mesh.faces + 3 * f;
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
      return Status::error(face_text(mesh, f) + ": degenerate, repeats a vertex");
  }
  return Status::success();
}

bool same_vertices(const AnimatedMeshView& mesh, int32_t f, int32_t g) {
  const int32_t* pf = mesh.faces + 3 * static_cast<size_t>(f);
  const int32_t* pg = mesh.faces + 3 * static_cast<size_t>(g);
  std::array<int32_t, 3> a{pf[0], pf[1], pf[2]};
  std::array<int32_t, 3> b{pg[0], pg[1], pg[2]};
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  return a == b;
}

Status duplicate_error(int32_t f, int32_t g) {
  return Status::error("faces " + std::to_string(std::min(f, g)) + " and " + std::to_string(std::max(f, g)) +
                       ": duplicate, same three vertices");
}

// Two faces on the same three vertices share every edge: either in the same direction (the
// edge table flags that edge) or in opposite directions with the same opposite vertex.
Status check_duplicate_faces(const AnimatedMeshView& mesh, const detail::EdgeTable& edges) {
  if (!edges.manifold) {
    const auto& bad = edges.bad_faces;
    for (int i = 0; i < 3; ++i)
      for (int j = i + 1; j < 3; ++j)
        if (bad[i] >= 0 && bad[j] >= 0 && same_vertices(mesh, bad[i], bad[j])) return duplicate_error(bad[i], bad[j]);
  }
  auto opposite = [&](int32_t face, const std::array<int32_t, 2>& edge) {
    const int32_t* v = mesh.faces + 3 * static_cast<size_t>(face);
    return v[0] != edge[0] && v[0] != edge[1] ? v[0] : v[1] != edge[0] && v[1] != edge[1] ? v[1] : v[2];
  };
  for (size_t e = 0; e < edges.size(); ++e) {
    if (edges.is_boundary(e)) continue;
    const auto [f, g] = edges.faces[e];
    if (opposite(f, edges.vertices[e]) == opposite(g, edges.vertices[e])) return duplicate_error(f, g);
  }
  return Status::success();
}

Status check_manifold_edges(const detail::EdgeTable& edges) {
  if (edges.manifold) return Status::success();
  const std::string edge =
      "edge (" + std::to_string(edges.bad_edge[0]) + ", " + std::to_string(edges.bad_edge[1]) + ")";
  if (edges.bad_faces[2] >= 0)
    return Status::error(edge + ": non-manifold, shared by three or more faces (" +
                         std::to_string(edges.bad_faces[0]) + ", " + std::to_string(edges.bad_faces[1]) + ", " +
                         std::to_string(edges.bad_faces[2]) + ")");
  return Status::error(edge + ": faces " + std::to_string(edges.bad_faces[0]) + " and " +
                       std::to_string(edges.bad_faces[1]) +
                       " traverse it in the same direction (inconsistent orientation or non-manifold)");
}

// Corners around a vertex are joined across every interior edge; a vertex whose corners end in
// more than one set has several separate fans (a "bow tie").
Status check_manifold_vertices(const AnimatedMeshView& mesh, const detail::EdgeTable& edges) {
  // 3 M fits int32 (check_sizes_and_values), so the corner index does too.
  auto corner_of = [&](int32_t face, int32_t vertex) {
    const size_t first = 3 * static_cast<size_t>(face);
    const int32_t* v = mesh.faces + first;
    return static_cast<int32_t>(first + (v[0] == vertex ? 0 : v[1] == vertex ? 1 : 2));
  };
  detail::UnionFind corners(3 * mesh.face_count);
  for (size_t e = 0; e < edges.size(); ++e) {
    if (edges.is_boundary(e)) continue;
    for (int32_t vertex : edges.vertices[e])
      corners.unite(corner_of(edges.faces[e][0], vertex), corner_of(edges.faces[e][1], vertex));
  }
  std::vector<int32_t> fan(mesh.vertex_count, -1);
  for (size_t c = 0; c < 3 * mesh.face_count; ++c) {
    const int32_t vertex = mesh.faces[c];
    const int32_t root = corners.find(static_cast<int32_t>(c));
    if (fan[vertex] < 0) fan[vertex] = root;
    else if (fan[vertex] != root)
      return Status::error("vertex " + std::to_string(vertex) +
                           ": non-manifold, its faces form separate fans joined only at the vertex");
  }
  for (size_t v = 0; v < mesh.vertex_count; ++v)
    if (fan[v] < 0) return Status::error("vertex " + std::to_string(v) + ": not referenced by any face");
  return Status::success();
}

}  // namespace

Status validate_animated_mesh(const AnimatedMeshView& mesh) {
  detail::EdgeTable edges;
  return detail::validate_and_build_edges(mesh, edges);
}

Status detail::check_sizes_values_and_indices(const AnimatedMeshView& mesh) { return check_sizes_and_values(mesh); }

Status detail::validate_and_build_edges(const AnimatedMeshView& mesh, EdgeTable& edges) {
  if (Status status = check_sizes_and_values(mesh); !status) return status;
  if (Status status = check_no_degenerate_faces(mesh); !status) return status;
  edges = build_edge_table(mesh.faces, mesh.face_count);
  if (Status status = check_duplicate_faces(mesh, edges); !status) return status;
  if (Status status = check_manifold_edges(edges); !status) return status;
  return check_manifold_vertices(mesh, edges);
}

}  // namespace animlod
