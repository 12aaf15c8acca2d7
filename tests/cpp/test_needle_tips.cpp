// Needle tips (needle_tips.hpp) and the point quadrics AQEM puts at them (option tip_quadrics).
#include <doctest/doctest.h>

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "animlod/aqem.hpp"
#include "aqem_level_checks.hpp"
#include "needle_tips.hpp"
#include "test_aqem_meshes.hpp"

using animlod::detail::find_needle_tips;

namespace {

struct PointMesh {
  std::vector<Eigen::Vector3d> points;
  std::vector<int32_t> faces;
  std::vector<int32_t> tips() const {
    return tips_in(0, static_cast<int32_t>(points.size()));
  }
  std::vector<int32_t> tips_in(int32_t begin, int32_t end) const {
    return find_needle_tips(faces, begin, end, [&](int32_t p) { return points[static_cast<size_t>(p)]; });
  }
};

// A closed square pyramid: base corners 0-3 at z = 0 (half-width 1), apex 4 at height `height`.
PointMesh pyramid(double height) {
  return {{{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {0, 0, height}},
          {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4, 0, 2, 1, 0, 3, 2}};
}

}  // namespace

TEST_CASE("needle tips: a spike's apex is one, a blunt apex, a cube's corners and a flat grid have none") {
  CHECK(pyramid(10.0).tips() == std::vector<int32_t>{4});  // edges 8 degrees from the axis
  CHECK(pyramid(1.5).tips() == std::vector<int32_t>{4});   // 43 degrees
  CHECK(pyramid(1.0).tips().empty());                      // 55 degrees: no needle
  PointMesh cube;
  for (int i = 0; i < 8; ++i) cube.points.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  cube.faces = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  CHECK(cube.tips().empty());  // every corner's edges 54.7 degrees from their mean
  const animlod::testing::OwnedAnimatedMesh grid = animlod::testing::grid(4);
  PointMesh flat{{}, grid.faces};
  for (size_t v = 0; v < grid.vertex_count; ++v)
    flat.points.emplace_back(grid.frames[3 * v], grid.frames[3 * v + 1], grid.frames[3 * v + 2]);
  for (int32_t tip : flat.tips()) CHECK(tip == 0);  // at most the corner with one 45-degree face
}

TEST_CASE("needle tips: zero-length edges give no direction and cancelling ones make no tip") {
  PointMesh doubled = pyramid(10.0);
  doubled.points.push_back(doubled.points[4]);  // point 5 on the apex
  doubled.faces.insert(doubled.faces.end(), {4, 5, 0});
  CHECK(doubled.tips() == std::vector<int32_t>{4, 5});
  // A degenerate face: point 0's edges cancel out; 1 and 2 each see the others in one direction.
  const PointMesh sliver{{{0, 0, 0}, {1, 0, 0}, {-1, 0, 0}}, {0, 1, 2}};
  CHECK(sliver.tips() == std::vector<int32_t>{1, 2});
}

TEST_CASE("needle tips: ranges of points searched apart give the whole mesh's tips") {
  // Three spikes side by side (apexes 4, 9 and 14), the middle one blunt: split at every point,
  // the two ranges' tips in order are the whole search's (the workers of aqem.cpp split so).
  PointMesh spikes;
  for (int s = 0; s < 3; ++s) {
    PointMesh one = pyramid(s == 1 ? 1.0 : 10.0);
    const auto offset = static_cast<int32_t>(spikes.points.size());
    for (const Eigen::Vector3d& p : one.points) spikes.points.push_back(p + Eigen::Vector3d(3.0 * s, 0, 0));
    for (int32_t corner : one.faces) spikes.faces.push_back(offset + corner);
  }
  const std::vector<int32_t> whole = spikes.tips();
  REQUIRE(whole == std::vector<int32_t>{4, 14});
  const auto points = static_cast<int32_t>(spikes.points.size());
  for (int32_t split = 0; split <= points; ++split) {
    std::vector<int32_t> parts = spikes.tips_in(0, split);
    const std::vector<int32_t> rest = spikes.tips_in(split, points);
    parts.insert(parts.end(), rest.begin(), rest.end());
    CHECK(parts == whole);
  }
}

TEST_CASE("tip quadrics change nothing on a mesh without needle tips") {
  const animlod::testing::OwnedAnimatedMesh mesh = animlod::testing::bending_tube(20, 12, 6, 1.5);
  animlod::AqemOptions with_tips, without;
  with_tips.target_ratios = without.target_ratios = {0.5, 0.2, 0.05};
  without.tip_quadrics = false;
  const animlod::AqemResult a = animlod::testing::simplify(mesh, with_tips);
  const animlod::AqemResult b = animlod::testing::simplify(mesh, without);
  REQUIRE(a.levels.size() == b.levels.size());
  for (size_t k = 0; k < a.levels.size(); ++k) {
    CHECK(a.levels[k].faces == b.levels[k].faces);
    CHECK(a.levels[k].positions == b.levels[k].positions);
  }
  CHECK(a.collapses.error == b.collapses.error);
}

TEST_CASE("tip quadrics hold a spike that is one in every frame, not a point that folds into one") {
  // A 4 x 4 grid whose middle point rises in frame 1 only (a transient cone), or in both.
  auto raised_grid = [](bool in_both_frames) {
    animlod::testing::OwnedAnimatedMesh mesh = animlod::testing::grid(4);
    const size_t middle = 12;  // (2, 2) of the 5 x 5 points
    std::vector<float> second = mesh.frames;
    second[3 * middle + 2] = 3.0f;
    if (in_both_frames) mesh.frames[3 * middle + 2] = 3.0f;
    mesh.frames.insert(mesh.frames.end(), second.begin(), second.end());
    mesh.frame_count = 2;
    return mesh;
  };
  for (bool in_both_frames : {false, true}) {
    CAPTURE(in_both_frames);
    const animlod::testing::OwnedAnimatedMesh mesh = raised_grid(in_both_frames);
    animlod::AqemOptions with_tips, without;
    with_tips.target_face_counts = without.target_face_counts = {2};  // the spike must go
    without.tip_quadrics = false;
    const animlod::AqemResult a = animlod::testing::simplify(mesh, with_tips);
    const animlod::AqemResult b = animlod::testing::simplify(mesh, without);
    CHECK((a.collapses.error == b.collapses.error) == !in_both_frames);
  }
}
