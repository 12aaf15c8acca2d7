#include <doctest/doctest.h>

#include <array>
#include <limits>
#include <vector>

#include "inversion_test.hpp"

using animlod::detail::face_keeps_orientation;

namespace {

constexpr double kEq7Alone = std::numeric_limits<double>::infinity();

// A triangle in z = 0 over F frames; frame f translates it by f along z (a rigid motion).
struct Triangle {
  std::vector<float> corner[3];
  explicit Triangle(size_t frames) {
    const float base[3][2] = {{0, 0}, {1, 0}, {0, 1}};
    for (int c = 0; c < 3; ++c)
      for (size_t f = 0; f < frames; ++f) corner[c].insert(corner[c].end(), {base[c][0], base[c][1], float(f)});
  }
  std::array<const float*, 3> pointers() const { return {corner[0].data(), corner[1].data(), corner[2].data()}; }
};

}  // namespace

TEST_CASE("Eq. 7 accepts a move that keeps the face's turn in every frame") {
  const Triangle face(3);
  std::vector<Eigen::Vector3d> placed = {{2, 0, 0}, {2, 0, 1}, {2, 0, 2}};  // corner 1 slides along x
  CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 3, kEq7Alone));
  CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 3, 0.0));
}

TEST_CASE("Eq. 7 rejects a move that flips the face in every frame") {
  const Triangle face(3);
  std::vector<Eigen::Vector3d> placed = {{-1, 0, 0}, {-1, 0, 1}, {-1, 0, 2}};  // corner 1 crosses the opposite side
  CHECK_FALSE(face_keeps_orientation(face.pointers(), 1, placed.data(), 3, kEq7Alone));
}

TEST_CASE("Eq. 7 weighs frames by area: a small flip in one frame is outvoted, unless the fold limit is 0") {
  const Triangle face(2);
  // Frame 0 keeps a large face; frame 1 flips it into a sliver.
  std::vector<Eigen::Vector3d> placed = {{3, 0, 0}, {-0.01, 0, 1}};
  CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, kEq7Alone));
  CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, 1.0));
  CHECK_FALSE(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, 0.0));
}

TEST_CASE("a fold in one frame is measured in lengths of the edge opposite the moved corner") {
  const Triangle face(2);
  // Corner 1 crosses the line x = 0 of the opposite edge (length 1) in frame 1 by 0.5 and 1.5;
  // frame 0's large face outvotes the flip in Eq. 7's sum either way.
  for (const double depth : {0.5, 1.5}) {
    std::vector<Eigen::Vector3d> placed = {{9, 0, 0}, {-depth, 0, 1}};
    REQUIRE(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, kEq7Alone));
    CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, 1.0) == (depth < 1.0));
    CHECK_FALSE(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, 0.25));
    CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, 2.0));
  }
}

TEST_CASE("Eq. 7 rejects a face whose area vanishes in every frame") {
  const Triangle face(2);
  std::vector<Eigen::Vector3d> placed = {{0, 0, 0}, {0, 0, 1}};  // corner 1 onto corner 0
  CHECK_FALSE(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, kEq7Alone));
}
