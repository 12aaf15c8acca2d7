#include <doctest/doctest.h>

#include <array>
#include <vector>

#include "inversion_test.hpp"

using animlod::detail::face_keeps_orientation;

namespace {

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
  CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 3, false));
  CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 3, true));
}

TEST_CASE("Eq. 7 rejects a move that flips the face in every frame") {
  const Triangle face(3);
  std::vector<Eigen::Vector3d> placed = {{-1, 0, 0}, {-1, 0, 1}, {-1, 0, 2}};  // corner 1 crosses the opposite side
  CHECK_FALSE(face_keeps_orientation(face.pointers(), 1, placed.data(), 3, false));
}

TEST_CASE("Eq. 7 weighs frames by area: a small flip in one frame is outvoted, unless strict") {
  const Triangle face(2);
  // Frame 0 keeps a large face; frame 1 flips it into a sliver.
  std::vector<Eigen::Vector3d> placed = {{3, 0, 0}, {-0.01, 0, 1}};
  CHECK(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, false));
  CHECK_FALSE(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, true));
}

TEST_CASE("Eq. 7 rejects a face whose area vanishes in every frame") {
  const Triangle face(2);
  std::vector<Eigen::Vector3d> placed = {{0, 0, 0}, {0, 0, 1}};  // corner 1 onto corner 0
  CHECK_FALSE(face_keeps_orientation(face.pointers(), 1, placed.data(), 2, false));
}
