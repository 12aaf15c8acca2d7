#include "inversion_test.hpp"

#include <cmath>

namespace animlod::detail {

bool face_keeps_orientation(const std::array<const float*, 3>& corners, int moved, const Eigen::Vector3d* placed,
                            size_t frame_count, bool strict) {
  double agreement = 0.0;
  bool has_area = false;
  for (size_t frame = 0; frame < frame_count; ++frame) {
    Eigen::Vector3d before[3], after[3];
    for (int c = 0; c < 3; ++c) {
      const float* p = corners[c] + 3 * frame;
      before[c] = Eigen::Vector3d(p[0], p[1], p[2]);
      after[c] = c == moved ? placed[frame] : before[c];
    }
    const Eigen::Vector3d n_before = (before[1] - before[0]).cross(before[2] - before[0]);
    const Eigen::Vector3d n_after = (after[1] - after[0]).cross(after[2] - after[0]);
    const double area_product = n_before.norm() * n_after.norm();
    if (area_product == 0.0) continue;
    has_area = true;
    const double dot = n_before.dot(n_after);
    if (strict && dot < 0.0) return false;
    // n . n' sqrt(A A') with n = N / |N| and A = |N| / 2.
    agreement += dot / (2.0 * std::sqrt(area_product));
  }
  return has_area && agreement >= 0.0;
}

}  // namespace animlod::detail
