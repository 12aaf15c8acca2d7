// OpenMesh's halfedge collapse without its fan walks, for an edge away from every border.
#pragma once

#include <OpenMesh/Core/Mesh/TriConnectivity.hh>

namespace animlod::detail {

// Collapses `halfedge` (its from-vertex into its to-vertex) as PolyConnectivity::collapse does
// in OpenMesh 9.0's source (collapse_edge, then collapse_loop on each side whose triangle became
// a 2-gon), element for element, less its five calls of adjust_outgoing_halfedge: each walks a
// whole fan looking for a border halfedge to make the vertex's outgoing one, which changes
// nothing where no vertex of the two faces lies on a border (every call here; the walks were 5%
// of the 1M case's CPU samples). Returns false, changing nothing, when one does: the caller then
// uses OpenMesh's collapse.
bool collapse_away_from_borders(OpenMesh::TriConnectivity& mesh, OpenMesh::TriConnectivity::HalfedgeHandle halfedge);

}  // namespace animlod::detail
