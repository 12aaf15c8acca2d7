// Small procedural animated meshes for the AQEM and motion-feature tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <array>
#include <cstdint>
#include <map>
#include <vector>

#include "animlod/animated_mesh_view.hpp"

namespace animlod::testing {

struct OwnedAnimatedMesh {
  std::vector<float> frames;    // (F, V, 3)
  std::vector<int32_t> faces;   // (M, 3)
  size_t frame_count = 0, vertex_count = 0;

  AnimatedMeshView view() const {
    return {frames.data(), faces.data(), frame_count, vertex_count, faces.size() / 3};
  }
};

// A flat (n+1) x (n+1) grid in z = 0 over [0, 1]^2, faces facing +z, one frame.
inline OwnedAnimatedMesh grid(int n) {
  OwnedAnimatedMesh mesh;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) mesh.frames.insert(mesh.frames.end(), {float(i) / n, float(j) / n, 0.0f});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.faces.insert(mesh.faces.end(), {a, b, d, a, d, c});
    }
  mesh.frame_count = 1;
  mesh.vertex_count = size_t(n + 1) * (n + 1);
  return mesh;
}

// grid(n) cut along x = 0.5 into two UV charts: the seam vertices get a copy for the right
// chart, whose UVs (x, y) lie 10 units over in u. `uvs` gets (V, 2).
inline OwnedAnimatedMesh grid_with_uv_seam(int n, std::vector<float>& uvs) {
  OwnedAnimatedMesh mesh = grid(n);
  uvs.clear();
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    const float x = mesh.frames[3 * v];
    uvs.insert(uvs.end(), {x > 0.5f ? x + 10.0f : x, mesh.frames[3 * v + 1]});
  }
  std::map<int32_t, int32_t> copy_of;  // seam vertex -> its copy for the right chart
  for (int j = 0; j <= n; ++j) {
    const int32_t v = j * (n + 1) + n / 2;
    copy_of[v] = static_cast<int32_t>(mesh.vertex_count++);
    mesh.frames.insert(mesh.frames.end(), {mesh.frames[3 * v], mesh.frames[3 * v + 1], mesh.frames[3 * v + 2]});
    uvs.insert(uvs.end(), {mesh.frames[3 * v] + 10.0f, mesh.frames[3 * v + 1]});
  }
  for (size_t f = 0; f < mesh.faces.size(); f += 3) {
    float centre = 0.0f;
    for (int k = 0; k < 3; ++k) centre += mesh.frames[3 * mesh.faces[f + k]] / 3.0f;
    if (centre > 0.5f)
      for (int k = 0; k < 3; ++k)
        if (copy_of.count(mesh.faces[f + k])) mesh.faces[f + k] = copy_of[mesh.faces[f + k]];
  }
  return mesh;
}

// An open tube of radius 0.2 along x in [-1, 1] (rings x segments vertices), faces facing out.
// Frame f bends the half x > 0 about the z axis by angle f * bend / (F - 1), with a short
// blend zone around x = 0, like an elbow.
inline OwnedAnimatedMesh bending_tube(int rings, int segments, int frame_count, double bend) {
  OwnedAnimatedMesh mesh;
  mesh.frame_count = size_t(frame_count);
  mesh.vertex_count = size_t(rings) * segments;
  const double pi = 3.14159265358979323846;
  for (int f = 0; f < frame_count; ++f) {
    const double angle = frame_count > 1 ? bend * f / (frame_count - 1) : 0.0;
    for (int r = 0; r < rings; ++r) {
      const double x = -1.0 + 2.0 * r / (rings - 1);
      const double blend = std::clamp(x / 0.2 + 0.5, 0.0, 1.0);  // 0 left of the elbow, 1 right of it
      const double a = angle * blend;
      for (int s = 0; s < segments; ++s) {
        const double phi = 2.0 * pi * s / segments;
        const double px = x, py = 0.2 * std::cos(phi), pz = 0.2 * std::sin(phi);
        mesh.frames.insert(mesh.frames.end(), {float(std::cos(a) * px - std::sin(a) * py),
                                               float(std::sin(a) * px + std::cos(a) * py), float(pz)});
      }
    }
  }
  for (int r = 0; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const int32_t a = r * segments + s, b = r * segments + (s + 1) % segments;
      const int32_t c = a + segments, d = b + segments;
      mesh.faces.insert(mesh.faces.end(), {a, d, c, a, b, d});
    }
  return mesh;
}

// A closed latitude-longitude sphere of radius 1 (two poles), faces facing out; frame f
// scales it by (1 + 0.5 f, 1, 1 - 0.3 f / F) so that it deforms smoothly.
inline OwnedAnimatedMesh sphere(int rings, int segments, int frame_count) {
  OwnedAnimatedMesh mesh;
  mesh.frame_count = size_t(frame_count);
  mesh.vertex_count = size_t(rings - 1) * segments + 2;
  const double pi = 3.14159265358979323846;
  for (int f = 0; f < frame_count; ++f) {
    const double sx = 1.0 + 0.5 * f, sz = 1.0 - 0.3 * f / frame_count;
    mesh.frames.insert(mesh.frames.end(), {0.0f, 0.0f, float(sz)});
    for (int r = 1; r < rings; ++r) {
      const double theta = pi * r / rings;
      for (int s = 0; s < segments; ++s) {
        const double phi = 2.0 * pi * s / segments;
        mesh.frames.insert(mesh.frames.end(), {float(sx * std::sin(theta) * std::cos(phi)),
                                               float(std::sin(theta) * std::sin(phi)), float(sz * std::cos(theta))});
      }
    }
    mesh.frames.insert(mesh.frames.end(), {0.0f, 0.0f, float(-sz)});
  }
  const int32_t south = int32_t(mesh.vertex_count) - 1;
  auto ring_vertex = [segments](int r, int s) { return int32_t(1 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) mesh.faces.insert(mesh.faces.end(), {0, ring_vertex(1, s), ring_vertex(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const int32_t a = ring_vertex(r, s), b = ring_vertex(r, s + 1), c = ring_vertex(r + 1, s), d = ring_vertex(r + 1, s + 1);
      mesh.faces.insert(mesh.faces.end(), {a, c, d, a, d, b});
    }
  for (int s = 0; s < segments; ++s)
    mesh.faces.insert(mesh.faces.end(), {south, ring_vertex(rings - 1, s + 1), ring_vertex(rings - 1, s)});
  return mesh;
}

// The surface of the cube [0, 1]^3 with every side split into n x n cells (two triangles
// each), vertices shared, faces facing out, one frame.
inline OwnedAnimatedMesh subdivided_cube(int n) {
  OwnedAnimatedMesh mesh;
  std::map<std::array<int, 3>, int32_t> index;
  auto vertex = [&](std::array<int, 3> lattice) {
    auto [it, added] = index.emplace(lattice, int32_t(index.size()));
    if (added)
      for (int k = 0; k < 3; ++k) mesh.frames.push_back(float(lattice[k]) / n);
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      // (u, v, axis) is right-handed for side 1; side 0 swaps u and v to face -axis.
      const int u_axis = (axis + 1 + (1 - side)) % 3, v_axis = (axis + 2 - (1 - side)) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto corner = [&](int di, int dj) {
            std::array<int, 3> lattice{};
            lattice[axis] = side * n;
            lattice[u_axis] = i + di;
            lattice[v_axis] = j + dj;
            return vertex(lattice);
          };
          const int32_t a = corner(0, 0), b = corner(1, 0), c = corner(1, 1), d = corner(0, 1);
          mesh.faces.insert(mesh.faces.end(), {a, b, c, a, c, d});
        }
    }
  mesh.frame_count = 1;
  mesh.vertex_count = index.size();
  return mesh;
}

// sphere(rings, segments, 1) in frame 0, then frames whose coordinates each move by a uniform
// pseudo-random offset in [-amplitude, amplitude] from it: a still surface with capture noise.
inline OwnedAnimatedMesh jittering_sphere(int rings, int segments, int frame_count, float amplitude) {
  OwnedAnimatedMesh mesh = sphere(rings, segments, 1);
  const std::vector<float> rest = mesh.frames;
  uint32_t state = 12345u;  // a linear congruential generator: the same noise on every platform
  for (int f = 1; f < frame_count; ++f)
    for (float value : rest) {
      state = state * 1664525u + 1013904223u;
      mesh.frames.push_back(value + amplitude * (2.0f * float(state >> 8) / float(1u << 24) - 1.0f));
    }
  mesh.frame_count = size_t(frame_count);
  return mesh;
}

}  // namespace animlod::testing
