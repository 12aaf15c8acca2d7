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

// The points in [point_begin, point_end) of `faces` (M, 3) that are needle tips with the
// positions position_of(point) (an Eigen::Vector3d), in increasing order; with `among` (P,),
// only points where it is nonzero are looked at. Zero-length edges give no direction; a point
// whose edge directions cancel out is no tip. A point's result does not depend on the range it
// is looked at in, so workers can take ranges of their own.
template <class PositionOf>
std::vector<int32_t> find_needle_tips(const std::vector<int32_t>& faces, int32_t point_begin, int32_t point_end,
                                      const PositionOf& position_of, const uint8_t* among = nullptr) {
  auto in_range = [=](int32_t point) { return point >= point_begin && point < point_end; };
  auto looked_at = [=](int32_t point) { return in_range(point) && (among == nullptr || among[point] != 0); };
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
  const size_t range = static_cast<size_t>(point_end - point_begin);  // arrays below: (range,)
  std::vector<Eigen::Vector3d> sum(range, Eigen::Vector3d::Zero());
  std::vector<int32_t> count(range, 0);
  for_each_face_side(looked_at, [&](int32_t point, const Eigen::Vector3d& unit) {
    sum[point - point_begin] += unit;
    ++count[point - point_begin];
  });
  // Every unit vector within the cone puts the sum's length above count * cos (so above 0):
  // the other points (all but a few on any surface, and those with no edge) need no second look.
  std::vector<uint8_t> candidate(range, 0);
  std::vector<double> least(range, 2.0);  // smallest cosine of an edge to the mean
  for (size_t k = 0; k < range; ++k) {
    const double length = sum[k].norm();
    if (length > kNeedleTipCosine * count[k]) {
      candidate[k] = 1;
      sum[k] /= length;
    }
  }
  for_each_face_side(
      [&](int32_t point) { return in_range(point) && candidate[point - point_begin] != 0; },
      [&](int32_t point, const Eigen::Vector3d& unit) {
        least[point - point_begin] = std::min(least[point - point_begin], unit.dot(sum[point - point_begin]));
      });
  std::vector<int32_t> tips;
  for (size_t k = 0; k < range; ++k)
    if (candidate[k] && least[k] > kNeedleTipCosine) tips.push_back(point_begin + static_cast<int32_t>(k));
  return tips;
}

}  // namespace animlod::detail
