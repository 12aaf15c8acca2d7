// Needle tips: the points of a mesh whose edges all leave within 45 degrees of their mean
// direction: the end of a bird's leg or beak, the apex of a spike, a sharp corner. A spike's
// faces lie nearly parallel to it, so their plane quadrics charge moving its tip along the
// spike only a small fraction of the distance it moves (the distance times the sine of the
// spike's half-angle): quadric simplifiers collapse spikes onto their bases first (README, the
// Stork). AQEM adds a point quadric at each tip (aqem.cpp), so that a tip's error is its
// displacement.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace animlod::detail {

// cos 45 degrees: a cube's corner (edges 54.7 degrees from their mean) is no tip, a spike up to
// a right angle at its apex is.
inline const double kNeedleTipCosine = std::sqrt(0.5);

// The points of `faces` (M, 3) that are needle tips with the positions position_of(point)
// (an Eigen::Vector3d), in increasing order. Zero-length edges give no direction; a point
// whose edge directions cancel out is no tip.
template <class PositionOf>
std::vector<int32_t> find_needle_tips(const std::vector<int32_t>& faces, size_t point_count,
                                      const PositionOf& position_of) {
  std::vector<Eigen::Vector3d> mean(point_count, Eigen::Vector3d::Zero());
  std::vector<double> least(point_count, 2.0);  // smallest cosine of an edge to the mean
  // Each edge of a point is seen once per face beside it, which changes neither the mean's
  // direction much nor the smallest cosine.
  auto for_each_edge = [&](auto&& visit) {
    for (size_t corner = 0; corner < faces.size(); ++corner) {
      const size_t face = corner - corner % 3;
      const int32_t point = faces[corner];
      const Eigen::Vector3d at = position_of(point);
      for (size_t step : {size_t{1}, size_t{2}}) {
        const Eigen::Vector3d edge = position_of(faces[face + (corner - face + step) % 3]) - at;
        const double length = edge.norm();
        if (length > 0.0) visit(point, edge / length);
      }
    }
  };
  for_each_edge([&](int32_t point, const Eigen::Vector3d& unit) { mean[point] += unit; });
  for (Eigen::Vector3d& m : mean) m = m.norm() > 0.0 ? Eigen::Vector3d(m.normalized()) : Eigen::Vector3d::Zero();
  for_each_edge([&](int32_t point, const Eigen::Vector3d& unit) {
    least[point] = std::min(least[point], unit.dot(mean[point]));
  });
  std::vector<int32_t> tips;
  for (size_t point = 0; point < point_count; ++point)
    if (mean[point].squaredNorm() > 0.0 && least[point] > kNeedleTipCosine)  // a zero mean: no edge, or they cancel
      tips.push_back(static_cast<int32_t>(point));
  return tips;
}

}  // namespace animlod::detail
