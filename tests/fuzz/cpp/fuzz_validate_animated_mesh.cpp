// Fuzz harness: validate_animated_mesh on decoded meshes (layout in fuzz_input.hpp).
// Invariants: a failure has a message; an accepted mesh has finite positions, indices in range
// and no face repeating a vertex (the cheap part of the checks, recomputed here).
#include <cmath>

#include "animlod/mesh_validation.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  animlod::fuzz::FuzzInput in(data, size);
  const animlod::fuzz::FuzzMesh mesh = animlod::fuzz::decode_mesh(in);
  const animlod::Status status = animlod::validate_animated_mesh(mesh.view());
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
    return 0;
  }
  ANIMLOD_FUZZ_REQUIRE(mesh.face_count > 0);
  for (float value : mesh.frames) ANIMLOD_FUZZ_REQUIRE(std::isfinite(value));
  for (size_t f = 0; f < mesh.face_count; ++f) {
    const int32_t* v = &mesh.faces[3 * f];
    for (int k = 0; k < 3; ++k) ANIMLOD_FUZZ_REQUIRE(v[k] >= 0 && static_cast<size_t>(v[k]) < mesh.vertex_count);
    ANIMLOD_FUZZ_REQUIRE(v[0] != v[1] && v[1] != v[2] && v[0] != v[2]);
  }
  return 0;
}
