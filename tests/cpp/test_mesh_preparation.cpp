#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "../../cpp/src/mesh_preparation.hpp"
#include "test_aqem_meshes.hpp"

namespace {

using animlod::detail::next_corner;
using animlod::detail::PreparedMesh;

// On a surface with every directed edge once: a side is paired exactly with the side running
// the other way along its edge, and a side without one is a border (-1).
void check_side_partners(const PreparedMesh& prepared) {
  const std::vector<int32_t>& points = prepared.faces;
  const std::vector<int32_t>& partner = prepared.side_partners;
  REQUIRE(partner.size() == points.size());
  std::map<std::pair<int32_t, int32_t>, int32_t> side_corner;  // (from, to) -> corner
  for (size_t c = 0; c < points.size(); ++c) side_corner[{points[c], points[next_corner(c)]}] = static_cast<int32_t>(c);
  for (size_t c = 0; c < points.size(); ++c) {
    const auto opposite = side_corner.find({points[next_corner(c)], points[c]});
    CHECK(partner[c] == (opposite == side_corner.end() ? -1 : opposite->second));
  }
}

PreparedMesh prepare(const animlod::testing::OwnedAnimatedMesh& mesh) {
  return animlod::detail::prepare_mesh(mesh.view(), animlod::detail::WeldInput{});
}

}  // namespace

TEST_CASE("mesh preparation pairs every side with the side running the other way") {
  SUBCASE("a grid: few sides per point") { check_side_partners(prepare(animlod::testing::grid(6))); }
  SUBCASE("a disc fanned from its centre: 100 sides at one point, its faces out of turn order") {
    animlod::testing::OwnedAnimatedMesh mesh;
    mesh.frames = {0.0f, 0.0f, 0.0f};
    for (int k = 0; k < 100; ++k) {
      const double angle = 2.0 * 3.14159265358979 * k / 100;
      mesh.frames.insert(mesh.frames.end(), {static_cast<float>(std::cos(angle)), static_cast<float>(std::sin(angle)), 0.0f});
    }
    for (int j = 0; j < 100; ++j) {
      const int k = 37 * j % 100;
      mesh.faces.insert(mesh.faces.end(), {0, 1 + k, 1 + (k + 1) % 100});
    }
    mesh.frame_count = 1;
    mesh.vertex_count = 101;
    const PreparedMesh prepared = prepare(mesh);
    CHECK(prepared.split_points == 0);
    check_side_partners(prepared);
  }
}

TEST_CASE("the weld takes float noise for equality and nothing larger") {
  // Two triangles meeting along an edge whose two points are written twice, the copies moved by
  // `offset` (as a seam written by two computations: sin(2 pi) for sin(0)), in the second frame
  // only when `late`.
  auto points_of = [](float offset, bool late) {
    animlod::testing::OwnedAnimatedMesh mesh;
    const std::vector<float> rest = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    for (int frame = 0; frame < 2; ++frame) {
      std::vector<float> positions = rest;
      if (frame == 1 || !late) positions[11] += offset, positions[14] -= offset;  // copies 3 and 4, off the plane
      mesh.frames.insert(mesh.frames.end(), positions.begin(), positions.end());
    }
    mesh.faces = {0, 1, 2, 4, 3, 5};
    mesh.frame_count = 2;
    mesh.vertex_count = 6;
    return prepare(mesh).point_source.size();
  };
  CHECK(points_of(0.0f, false) == 4);
  CHECK(points_of(2.4e-16f, false) == 4);  // the noise of sin(2 pi)
  CHECK(points_of(1e-7f, true) == 4);      // a float ulp at the extent, in one frame
  CHECK(points_of(1e-4f, false) == 6);     // a gap of 1e-4 of the extent is a gap
  CHECK(points_of(1e-4f, true) == 6);
}
