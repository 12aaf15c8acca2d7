#include <doctest/doctest.h>

#include <vector>

#include <OpenMesh/Core/Mesh/TriConnectivity.hh>

#include "../../cpp/src/interior_collapse.hpp"

namespace {

using Mesh = OpenMesh::TriConnectivity;

// An n x n grid of vertices in triangles, with a border all around.
Mesh grid(int n) {
  Mesh mesh;
  mesh.request_vertex_status();
  mesh.request_edge_status();
  mesh.request_face_status();
  for (int i = 0; i < n * n; ++i) mesh.new_vertex();
  auto at = [n](int row, int column) { return OpenMesh::VertexHandle(row * n + column); };
  for (int row = 0; row + 1 < n; ++row)
    for (int column = 0; column + 1 < n; ++column) {
      mesh.add_face(at(row, column), at(row, column + 1), at(row + 1, column + 1));
      mesh.add_face(at(row, column), at(row + 1, column + 1), at(row + 1, column));
    }
  return mesh;
}

// Every record and status flag of the two meshes, element for element.
void check_same(const Mesh& a, const Mesh& b) {
  for (size_t v = 0; v < a.n_vertices(); ++v) {
    const OpenMesh::VertexHandle vertex(static_cast<int>(v));
    CHECK(a.halfedge_handle(vertex) == b.halfedge_handle(vertex));
    CHECK(a.status(vertex).deleted() == b.status(vertex).deleted());
  }
  for (size_t h = 0; h < a.n_halfedges(); ++h) {
    const OpenMesh::HalfedgeHandle halfedge(static_cast<int>(h));
    CHECK(a.next_halfedge_handle(halfedge) == b.next_halfedge_handle(halfedge));
    CHECK(a.prev_halfedge_handle(halfedge) == b.prev_halfedge_handle(halfedge));
    CHECK(a.to_vertex_handle(halfedge) == b.to_vertex_handle(halfedge));
    CHECK(a.face_handle(halfedge) == b.face_handle(halfedge));
  }
  for (size_t e = 0; e < a.n_edges(); ++e)
    CHECK(a.status(OpenMesh::EdgeHandle(static_cast<int>(e))).deleted() ==
          b.status(OpenMesh::EdgeHandle(static_cast<int>(e))).deleted());
  for (size_t f = 0; f < a.n_faces(); ++f) {
    const OpenMesh::FaceHandle face(static_cast<int>(f));
    CHECK(a.halfedge_handle(face) == b.halfedge_handle(face));
    CHECK(a.status(face).deleted() == b.status(face).deleted());
  }
}

}  // namespace

TEST_CASE("a collapse away from borders leaves every record as OpenMesh's collapse does") {
  const Mesh start = grid(7);
  int collapsed = 0, refused = 0;
  for (size_t h = 0; h < start.n_halfedges(); ++h) {
    const OpenMesh::HalfedgeHandle halfedge(static_cast<int>(h));
    Mesh ours = start, theirs = start;
    if (!theirs.is_collapse_ok(halfedge)) continue;
    theirs.collapse(halfedge);
    if (animlod::detail::collapse_away_from_borders(ours, halfedge)) ++collapsed;
    else {
      ++refused;
      check_same(ours, start);  // unchanged
      ours.collapse(halfedge);
    }
    check_same(ours, theirs);
  }
  CHECK(collapsed > 0);
  CHECK(refused > 0);
  // A sequence of collapses, each checked against OpenMesh's.
  Mesh ours = grid(9), theirs = grid(9);
  for (int round = 0; round < 3; ++round)
    for (size_t h = 0; h < theirs.n_halfedges(); h += 7) {
      const OpenMesh::HalfedgeHandle halfedge(static_cast<int>(h));
      if (!theirs.is_collapse_ok(halfedge)) continue;
      theirs.collapse(halfedge);
      if (!animlod::detail::collapse_away_from_borders(ours, halfedge)) ours.collapse(halfedge);
      check_same(ours, theirs);
    }
}
