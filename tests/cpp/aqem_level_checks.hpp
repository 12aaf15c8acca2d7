// Checks of AQEM levels shared by the doctest files: run to success, manifold output, no face
// turned inside out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <set>
#include <utility>

#include <doctest/doctest.h>

#include "animlod/aqem.hpp"
#include "test_aqem_meshes.hpp"

namespace animlod::testing {

inline AqemResult simplify(const OwnedAnimatedMesh& mesh, const AqemOptions& options, const AqemVertexData& data = {}) {
  AqemResult result;
  const animlod::Status status = simplify_animated(mesh.view(), data, options, result);
  REQUIRE_MESSAGE(status.ok, status.message);
  return result;
}

// Every undirected edge of the level has one or two faces, each direction used once.
inline bool is_manifold(const AqemLevel& level) {
  std::set<std::pair<int32_t, int32_t>> directed;
  for (size_t f = 0; f < level.faces.size(); f += 3)
    for (int k = 0; k < 3; ++k)
      if (!directed.insert({level.faces[f + k], level.faces[f + (k + 1) % 3]}).second) return false;
  return true;
}

// Faces of a level whose normal points towards the origin, over every frame. The test
// shapes are convex and centred at the origin, so an outward face has n . centroid > 0.
inline size_t inward_faces(const AqemLevel& level, size_t frame_count) {
  const size_t kept = level.kept_vertices.size();
  size_t inward = 0;
  for (size_t f = 0; f < frame_count; ++f) {
    const float* p = &level.positions[f * kept * 3];
    for (size_t t = 0; t < level.faces.size(); t += 3) {
      double a[3], b[3], c[3];
      for (int k = 0; k < 3; ++k) {
        a[k] = p[3 * level.faces[t] + k];
        b[k] = p[3 * level.faces[t + 1] + k];
        c[k] = p[3 * level.faces[t + 2] + k];
      }
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
      if (n[0] * (a[0] + b[0] + c[0]) + n[1] * (a[1] + b[1] + c[1]) + n[2] * (a[2] + b[2] + c[2]) <= 0.0) ++inward;
    }
  }
  return inward;
}

}  // namespace animlod::testing
