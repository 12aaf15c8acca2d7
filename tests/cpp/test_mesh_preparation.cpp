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
