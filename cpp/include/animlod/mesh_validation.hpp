// Input checks shared by every algorithm that takes an animated mesh.
#pragma once

#include "animlod/animated_mesh_view.hpp"
#include "animlod/status.hpp"

namespace animlod {

// Returns an error naming the first offending element for: no frames or faces, more than
// INT32_MAX vertices or INT32_MAX / 3 faces (indices are int32), a non-finite
// position, a face index outside [0, V), a face that repeats a vertex, two faces on the same
// three vertices, an edge shared by more than two faces, an edge traversed twice in the same
// direction (inconsistent orientation), a non-manifold vertex (faces forming separate fans),
// or a vertex no face references.
Status validate_animated_mesh(const AnimatedMeshView& mesh);

}  // namespace animlod
