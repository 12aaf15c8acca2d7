// Checks of AQEM levels shared by the doctest files: run to success, manifold output, no face
// turned inside out, attribute seams kept.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <set>
#include <utility>
#include <vector>

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

// Two attributes (UVs) and two skin influences per vertex, as the tests below give them.
inline AqemVertexData uvs_and_two_influences(const std::vector<float>& uvs, const std::vector<int32_t>& joints,
                                             const std::vector<float>& weights) {
  AqemVertexData data;
  data.attributes = uvs.data();
  data.attribute_count = 2;
  data.skin_joints = joints.data();
  data.skin_weights = weights.data();
  data.influence_count = 2;
  return data;
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

// A level of grid_with_uv_seam: every face lies on one side of the seam x = 0.5 with all its UVs
// from that side's chart, and both sides keep vertices on the seam line, at equal positions.
inline void check_uv_seam_kept(const AqemLevel& level) {
  for (size_t f = 0; f < level.faces.size(); f += 3) {
    float centre = 0.0f;
    int right_uvs = 0;
    for (int k = 0; k < 3; ++k) {
      centre += level.positions[3 * level.faces[f + k]] / 3.0f;
      right_uvs += level.attributes[2 * level.faces[f + k]] > 5.0f;
    }
    CHECK(right_uvs == (centre > 0.5f ? 3 : 0));
  }
  size_t left = 0, right = 0;
  for (size_t i = 0; i < level.kept_vertices.size(); ++i)
    if (std::fabs(level.positions[3 * i] - 0.5f) < 1e-6f) ++(level.attributes[2 * i] > 5.0f ? right : left);
  CHECK(left >= 2);
  CHECK(left == right);
}

}  // namespace animlod::testing
