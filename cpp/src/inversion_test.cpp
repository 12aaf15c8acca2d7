#include "inversion_test.hpp"

#include <cmath>

namespace animlod::detail {

namespace {

struct Vec3 {
  double x, y, z;
};

Vec3 minus(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
// Eigen's cross and dot products term for term (and its order of sums): the same bits as the
// Eigen code this replaced, with the moved corner known at compile time (kMoved).
Vec3 cross(const Vec3& a, const Vec3& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(const Vec3& a, const Vec3& b) { return (a.x * b.x + a.y * b.y) + a.z * b.z; }

template <int kMoved>
bool keeps_orientation(const std::array<const float*, 3>& corners, const Eigen::Vector3d* placed, size_t frame_count,
                       double fold_limit) {
  double agreement = 0.0;
  bool has_area = false;
  for (size_t frame = 0; frame < frame_count; ++frame) {
    Vec3 before[3], after[3];
    for (int c = 0; c < 3; ++c) {
      const float* p = corners[c] + 3 * frame;
      before[c] = after[c] = {p[0], p[1], p[2]};
    }
    after[kMoved] = {placed[frame].x(), placed[frame].y(), placed[frame].z()};
    const Vec3 n_before = cross(minus(before[1], before[0]), minus(before[2], before[0]));
    const Vec3 n_after = cross(minus(after[1], after[0]), minus(after[2], after[0]));
    const double area_product = std::sqrt(dot(n_before, n_before)) * std::sqrt(dot(n_after, n_after));
    if (area_product == 0.0) continue;
    has_area = true;
    const double normals = dot(n_before, n_after);
    if (normals < 0.0) {
      // n' . N / |N| = |ab| times the moved corner's signed distance from the line of the
      // opposite edge ab, within the face's plane: the fold's depth, here in units of |ab|.
      const Vec3 ab = minus(before[(kMoved + 2) % 3], before[(kMoved + 1) % 3]);
      if (-normals / (std::sqrt(dot(n_before, n_before)) * dot(ab, ab)) > fold_limit) return false;
    }
    // n . n' sqrt(A A') with n = N / |N| and A = |N| / 2.
    agreement += normals / (2.0 * std::sqrt(area_product));
  }
  return has_area && agreement >= 0.0;
}

}  // namespace

bool face_keeps_orientation(const std::array<const float*, 3>& corners, int moved, const Eigen::Vector3d* placed,
                            size_t frame_count, double fold_limit) {
  switch (moved) {
    case 0: return keeps_orientation<0>(corners, placed, frame_count, fold_limit);
    case 1: return keeps_orientation<1>(corners, placed, frame_count, fold_limit);
    default: return keeps_orientation<2>(corners, placed, frame_count, fold_limit);
  }
}

}  // namespace animlod::detail
