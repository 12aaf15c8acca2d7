#include "noise_floor.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace animlod::detail {

namespace {

constexpr size_t kMostEdges = 16384;

double diagonal(const float* points, size_t count) {
  std::array<double, 3> low{points[0], points[1], points[2]}, high = low;
  for (size_t p = 0; p < count; ++p)
    for (int axis = 0; axis < 3; ++axis) {
      low[axis] = std::min(low[axis], double(points[3 * p + axis]));
      high[axis] = std::max(high[axis], double(points[3 * p + axis]));
    }
  return std::hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]);
}

}  // namespace

double frame_noise_floor(const AnimatedMeshView& mesh) {
  if (mesh.frame_count < 2 || mesh.vertex_count == 0 || mesh.face_count == 0) return 0.0;
  const double size = diagonal(mesh.frames, mesh.vertex_count);
  if (!(size > 0.0)) return 0.0;
  // Each edge once: a face's edge from its lower to its higher corner index (an interior edge
  // of a consistently oriented surface runs the other way in its other face).
  std::vector<std::array<int32_t, 2>> edges;
  for (size_t corner = 0; corner < 3 * mesh.face_count; ++corner) {
    const int32_t from = mesh.faces[corner];
    const int32_t to = mesh.faces[corner % 3 == 2 ? corner - 2 : corner + 1];
    if (from < to) edges.push_back({from, to});
  }
  if (edges.empty()) return 0.0;
  const size_t stride = (edges.size() + kMostEdges - 1) / kMostEdges;
  std::vector<double> spreads;
  spreads.reserve(edges.size() / stride + 1);
  const size_t frame_size = 3 * mesh.vertex_count;
  for (size_t e = 0; e < edges.size(); e += stride) {
    double sum = 0.0, squares = 0.0;
    for (size_t frame = 0; frame < mesh.frame_count; ++frame) {
      const float* a = mesh.frames + frame * frame_size + 3 * static_cast<size_t>(edges[e][0]);
      const float* b = mesh.frames + frame * frame_size + 3 * static_cast<size_t>(edges[e][1]);
      const double length = std::hypot(double(a[0]) - b[0], double(a[1]) - b[1], double(a[2]) - b[2]);
      sum += length;
      squares += length * length;
    }
    const double mean = sum / double(mesh.frame_count);
    spreads.push_back(std::sqrt(std::max(squares / double(mesh.frame_count) - mean * mean, 0.0)));
  }
  const auto tenth = spreads.begin() + static_cast<std::ptrdiff_t>(spreads.size() / 10);
  std::nth_element(spreads.begin(), tenth, spreads.end());
  return *tenth / size;
}

}  // namespace animlod::detail
