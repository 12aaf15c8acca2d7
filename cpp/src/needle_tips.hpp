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
// (an Eigen::Vector3d), in increasing order; with `among` (P,), only points where it is nonzero
// are looked at. Zero-length edges give no direction; a point whose edge directions cancel out
// is no tip.
template <class PositionOf>
std::vector<int32_t> find_needle_tips(const std::vector<int32_t>& faces, size_t point_count,
                                      const PositionOf& position_of, const uint8_t* among = nullptr) {
  auto looked_at = [among](int32_t point) { return among == nullptr || among[point] != 0; };
  // Each edge of a point is seen once per face beside it, which changes neither the mean's
  // direction much nor the smallest cosine. Per face, its three sides' unit vectors serve both
  // of their points (the one they leave and, reversed, the one they reach).
  auto for_each_face_side = [&](auto&& wanted, auto&& visit) {
    for (size_t face = 0; face < faces.size(); face += 3) {
      const int32_t corners[3] = {faces[face], faces[face + 1], faces[face + 2]};
      if (!wanted(corners[0]) && !wanted(corners[1]) && !wanted(corners[2])) continue;
      const Eigen::Vector3d at[3] = {position_of(corners[0]), position_of(corners[1]), position_of(corners[2])};
      for (int side = 0; side < 3; ++side) {
        const int32_t from = corners[side], to = corners[(side + 1) % 3];
        const Eigen::Vector3d edge = at[(side + 1) % 3] - at[side];
        const double length = edge.norm();
        if (length == 0.0) continue;
        if (wanted(from)) visit(from, edge / length);
        if (wanted(to)) visit(to, -edge / length);
      }
    }
  };
  std::vector<Eigen::Vector3d> sum(point_count, Eigen::Vector3d::Zero());
  std::vector<int32_t> count(point_count, 0);
  for_each_face_side(looked_at, [&](int32_t point, const Eigen::Vector3d& unit) {
    sum[point] += unit;
    ++count[point];
  });
  // Every unit vector within the cone puts the sum's length above count * cos (so above 0):
  // the other points (all but a few on any surface, and those with no edge) need no second look.
  std::vector<uint8_t> candidate(point_count, 0);
  std::vector<double> least(point_count, 2.0);  // smallest cosine of an edge to the mean
  for (size_t point = 0; point < point_count; ++point) {
    const double length = sum[point].norm();
    if (length > kNeedleTipCosine * count[point]) {
      candidate[point] = 1;
      sum[point] /= length;
    }
  }
  for_each_face_side([&](int32_t point) { return candidate[point] != 0; },
                     [&](int32_t point, const Eigen::Vector3d& unit) {
                       least[point] = std::min(least[point], unit.dot(sum[point]));
                     });
  std::vector<int32_t> tips;
  for (size_t point = 0; point < point_count; ++point)
    if (candidate[point] && least[point] > kNeedleTipCosine) tips.push_back(static_cast<int32_t>(point));
  return tips;
}

}  // namespace animlod::detail
