#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "animlod/tdag_affine.hpp"
#include "test_aqem_meshes.hpp"

using animlod::AffineBase;
using animlod::AffineSplit;
using animlod::testing::OwnedAnimatedMesh;

namespace {

// Frame f of the result: frame 0 of `mesh` moved by the affine map maps[f] (3 x 4 row-major).
OwnedAnimatedMesh moved(const OwnedAnimatedMesh& mesh, const std::vector<std::vector<double>>& maps) {
  OwnedAnimatedMesh out = mesh;
  out.frame_count = maps.size();
  out.frames.resize(maps.size() * mesh.vertex_count * 3);
  for (size_t f = 0; f < maps.size(); ++f)
    animlod::apply_affine(maps[f].data(), mesh.frames.data(), mesh.vertex_count, &out.frames[f * mesh.vertex_count * 3]);
  return out;
}

}  // namespace

TEST_CASE("affine split recovers a known affine motion: the residuals equal the base") {
  const OwnedAnimatedMesh sphere = animlod::testing::sphere(8, 12, 1);
  std::vector<std::vector<double>> maps;
  for (int f = 0; f < 4; ++f) {
    const double a = 0.3 * f, s = 1.0 + 0.2 * f, shear = 0.1 * f;
    // Rotation about z, an anisotropic scale and a shear, then a translation far from the origin.
    maps.push_back({s * std::cos(a), -std::sin(a) + shear, 0.0, 100.0 + f,  //
                    s * std::sin(a), std::cos(a), 0.0, -50.0 + 2.0 * f,      //
                    0.0, 0.2 * f, 1.0 - 0.1 * f, 7.0});
  }
  maps[0] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  const OwnedAnimatedMesh mesh = moved(sphere, maps);
  AffineSplit split;
  REQUIRE(animlod::affine_split(mesh.view(), AffineBase::first, split).ok);
  for (size_t f = 0; f < maps.size(); ++f) {
    CHECK_FALSE(split.translation_only[f]);
    for (int i = 0; i < 12; ++i) CHECK(split.maps[f * 12 + i] == doctest::Approx(maps[f][i]).epsilon(1e-5));
    for (size_t i = 0; i < sphere.vertex_count * 3; ++i)
      CHECK(split.residuals[f * sphere.vertex_count * 3 + i] == doctest::Approx(sphere.frames[i]).epsilon(1e-4));
  }
  // Mapping the residuals forward gives the frames back.
  std::vector<float> rebuilt(sphere.vertex_count * 3);
  animlod::apply_affine(&split.maps[36], &split.residuals[3 * sphere.vertex_count * 3], sphere.vertex_count,
                        rebuilt.data());
  for (size_t i = 0; i < rebuilt.size(); ++i)
    CHECK(rebuilt[i] == doctest::Approx(mesh.frames[3 * sphere.vertex_count * 3 + i]).epsilon(1e-5));
}

TEST_CASE("affine split against the average mesh, a non-affine bend leaves a residual") {
  const OwnedAnimatedMesh tube = animlod::testing::bending_tube(12, 10, 5, 1.2);
  AffineSplit split;
  REQUIRE(animlod::affine_split(tube.view(), AffineBase::average, split).ok);
  // The average base: the residuals of all frames average to about the base, and the bent
  // frames are not an affine image of it, so some residual moves between frames.
  double moved_most = 0.0;
  for (size_t i = 0; i < tube.vertex_count * 3; ++i)
    moved_most = std::max(moved_most, double(std::fabs(split.residuals[4 * tube.vertex_count * 3 + i] - split.residuals[i])));
  CHECK(moved_most > 0.05);
}

TEST_CASE("affine split of a flat base falls back on translations, bad input is named") {
  OwnedAnimatedMesh grid = animlod::testing::grid(4);  // z = 0: a singular base
  grid.frame_count = 2;
  const std::vector<float> first = grid.frames;
  grid.frames.insert(grid.frames.end(), first.begin(), first.end());
  for (size_t v = 0; v < grid.vertex_count; ++v) grid.frames[(grid.vertex_count + v) * 3 + 2] += 1.5f;
  AffineSplit split;
  REQUIRE(animlod::affine_split(grid.view(), AffineBase::first, split).ok);
  CHECK(split.translation_only[1]);
  CHECK(split.maps[12 + 11] == doctest::Approx(1.5));
  for (size_t i = 0; i < grid.vertex_count * 3; ++i)
    CHECK(split.residuals[grid.vertex_count * 3 + i] == doctest::Approx(first[i]));

  grid.frames[(grid.vertex_count + 3) * 3 + 1] = NAN;
  const animlod::Status status = animlod::affine_split(grid.view(), AffineBase::first, split);
  CHECK_FALSE(status.ok);
  CHECK(status.message == "frame 1, vertex 3: non-finite position");
}

TEST_CASE("affine split of chosen vertices equals the split of a mesh of those vertices alone") {
  const OwnedAnimatedMesh tube = animlod::testing::bending_tube(12, 10, 5, 1.2);
  const std::vector<int32_t> chosen = {7, 3, 3, 50, 0, 119, 64, 21};  // any order, repeats too
  OwnedAnimatedMesh alone = tube;
  alone.vertex_count = chosen.size();
  alone.frames.clear();
  for (size_t f = 0; f < tube.frame_count; ++f)
    for (int32_t v : chosen)
      for (size_t k = 0; k < 3; ++k) alone.frames.push_back(tube.frames[(f * tube.vertex_count + size_t(v)) * 3 + k]);
  for (AffineBase base : {AffineBase::first, AffineBase::average}) {
    AffineSplit expected, found;
    REQUIRE(animlod::affine_split(alone.view(), base, expected).ok);
    REQUIRE(animlod::affine_split(tube.view(), chosen.data(), chosen.size(), base, found).ok);
    CHECK(found.maps == expected.maps);
    CHECK(found.residuals == expected.residuals);
    CHECK(found.translation_only == expected.translation_only);
  }
  AffineSplit split;
  const std::vector<int32_t> outside = {0, 120};
  CHECK(animlod::affine_split(tube.view(), outside.data(), outside.size(), AffineBase::first, split).message ==
        "vertices: 120 outside [0, 120)");
  CHECK(animlod::affine_split(tube.view(), outside.data(), 0, AffineBase::first, split).message == "vertices: none selected");
}
