// The validation of animlod/mesh_validation.hpp, keeping the edge table it builds, for
// callers that need the edges next (motion features). Defined in mesh_validation.cpp.
#pragma once

#include "animlod/animated_mesh_view.hpp"
#include "animlod/status.hpp"
#include "edge_table.hpp"

namespace animlod::detail {

// The first checks of validate_animated_mesh: frames and faces present, sizes within int32
// indices, finite positions, face indices in [0, V). What any indexed triangle mesh must pass.
Status check_sizes_values_and_indices(const AnimatedMeshView& mesh);

// validate_animated_mesh, filling `edges` (complete only when the status is success).
Status validate_and_build_edges(const AnimatedMeshView& mesh, EdgeTable& edges);

}  // namespace animlod::detail
