// The validation of animlod/mesh_validation.hpp, keeping the edge table it builds, for
// callers that need the edges next (motion features). Defined in mesh_validation.cpp.
#pragma once

#include "animlod/animated_mesh_view.hpp"
#include "animlod/status.hpp"
#include "edge_table.hpp"

namespace animlod::detail {

// validate_animated_mesh, filling `edges` (complete only when the status is success).
Status validate_and_build_edges(const AnimatedMeshView& mesh, EdgeTable& edges);

}  // namespace animlod::detail
