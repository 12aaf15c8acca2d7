#include "interior_collapse.hpp"

namespace animlod::detail {

namespace {

using Mesh = OpenMesh::TriConnectivity;

// PolyConnectivity::collapse_loop without adjust_outgoing_halfedge.
void collapse_loop(Mesh& mesh, Mesh::HalfedgeHandle h0) {
  const auto h1 = mesh.next_halfedge_handle(h0);
  const auto o0 = mesh.opposite_halfedge_handle(h0);
  const auto o1 = mesh.opposite_halfedge_handle(h1);
  const auto v0 = mesh.to_vertex_handle(h0);
  const auto v1 = mesh.to_vertex_handle(h1);
  const auto fh = mesh.face_handle(h0);
  const auto fo = mesh.face_handle(o0);
  mesh.set_next_halfedge_handle(h1, mesh.next_halfedge_handle(o0));
  mesh.set_next_halfedge_handle(mesh.prev_halfedge_handle(o0), h1);
  mesh.set_face_handle(h1, fo);
  mesh.set_halfedge_handle(v0, h1);
  mesh.set_halfedge_handle(v1, o1);
  if (fo.is_valid() && mesh.halfedge_handle(fo) == o0) mesh.set_halfedge_handle(fo, h1);
  if (fh.is_valid()) {
    mesh.set_halfedge_handle(fh, Mesh::InvalidHalfedgeHandle);
    mesh.status(fh).set_deleted(true);
  }
  mesh.status(mesh.edge_handle(h0)).set_deleted(true);
}

}  // namespace

bool collapse_away_from_borders(Mesh& mesh, Mesh::HalfedgeHandle h) {
  const auto o = mesh.opposite_halfedge_handle(h);
  const auto vh = mesh.to_vertex_handle(h), vo = mesh.to_vertex_handle(o);
  if (mesh.is_boundary(h) || mesh.is_boundary(o) || mesh.is_boundary(vh) || mesh.is_boundary(vo)) return false;
  const auto hn = mesh.next_halfedge_handle(h), hp = mesh.prev_halfedge_handle(h);
  const auto on = mesh.next_halfedge_handle(o), op = mesh.prev_halfedge_handle(o);
  if (mesh.is_boundary(mesh.to_vertex_handle(hn)) || mesh.is_boundary(mesh.to_vertex_handle(on))) return false;

  // collapse_edge
  const auto fh = mesh.face_handle(h), fo = mesh.face_handle(o);
  for (const auto incoming : mesh.vih_range(vo)) mesh.set_vertex_handle(incoming, vh);
  mesh.set_next_halfedge_handle(hp, hn);
  mesh.set_next_halfedge_handle(op, on);
  mesh.set_halfedge_handle(fh, hn);
  mesh.set_halfedge_handle(fo, on);
  if (mesh.halfedge_handle(vh) == o) mesh.set_halfedge_handle(vh, hn);
  mesh.set_isolated(vo);
  mesh.status(mesh.edge_handle(h)).set_deleted(true);
  mesh.status(vo).set_deleted(true);

  // The two triangles are 2-gons now.
  if (mesh.next_halfedge_handle(mesh.next_halfedge_handle(hn)) == hn) collapse_loop(mesh, mesh.next_halfedge_handle(hn));
  if (mesh.next_halfedge_handle(mesh.next_halfedge_handle(on)) == on) collapse_loop(mesh, on);
  return true;
}

}  // namespace animlod::detail
