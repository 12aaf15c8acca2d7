#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "animlod/aqem.hpp"
#include "aqem_level_checks.hpp"
#include "test_aqem_meshes.hpp"

using animlod::AqemLevel;
using animlod::AqemOptions;
using animlod::AqemResult;
using animlod::AqemVertexData;
using animlod::simplify_animated;
using animlod::testing::OwnedAnimatedMesh;
using animlod::testing::inward_faces;
using animlod::testing::is_manifold;
using animlod::testing::simplify;

namespace {

std::string failure(const OwnedAnimatedMesh& mesh, const AqemOptions& options = {}) {
  AqemResult result;
  const animlod::Status status = simplify_animated(mesh.view(), {}, options, result);
  CHECK_FALSE(status.ok);
  return status.message;
}

}  // namespace

TEST_CASE("aqem keeps a flat grid flat and inside its square, at or below the target") {
  const OwnedAnimatedMesh mesh = animlod::testing::grid(8);  // 128 faces
  AqemOptions options;
  options.target_ratios = {0.5, 0.25, 0.1};
  const AqemResult result = simplify(mesh, options);
  REQUIRE(result.levels.size() == 3);
  const size_t targets[] = {64, 32, 13};
  for (size_t i = 0; i < 3; ++i) {
    const AqemLevel& level = result.levels[i];
    CHECK(level.reached);
    CHECK(level.target_face_count == targets[i]);
    CHECK(level.faces.size() / 3 <= targets[i]);
    CHECK(is_manifold(level));
    CHECK(level.error == doctest::Approx(0.0));
    for (size_t v = 0; v < level.positions.size(); v += 3) {
      CHECK(level.positions[v + 2] == doctest::Approx(0.0));
      CHECK(level.positions[v] >= -1e-6f);
      CHECK(level.positions[v] <= 1.0f + 1e-6f);
    }
    for (int32_t index : level.faces) CHECK((index >= 0 && size_t(index) < level.kept_vertices.size()));
  }
  // The four corners are fixed by the boundary planes of two sides.
  const AqemLevel& coarsest = result.levels[2];
  for (int32_t corner : {0, 8, 72, 80})
    CHECK(std::count(coarsest.kept_vertices.begin(), coarsest.kept_vertices.end(), corner) == 1);
}

TEST_CASE("aqem levels come from one collapse sequence, with growing error") {
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(12, 16, 3);
  AqemOptions options;
  options.target_ratios = {0.1, 0.5, 0.25};  // any order; levels come finest first
  const AqemResult result = simplify(mesh, options);
  REQUIRE(result.levels.size() == 3);
  const size_t collapses = result.collapses.removed.size();
  CHECK(result.collapses.positions.size() == collapses * 3 * mesh.frame_count);
  for (size_t i = 0; i + 1 < 3; ++i) {
    CHECK(result.levels[i].target_face_count > result.levels[i + 1].target_face_count);
    CHECK(result.levels[i].collapse_count < result.levels[i + 1].collapse_count);
    CHECK(result.levels[i].error <= result.levels[i + 1].error);
  }
  CHECK(result.levels[2].collapse_count == collapses);
  // A closed mesh loses two faces and one vertex per collapse.
  for (const AqemLevel& level : result.levels) {
    CHECK(level.faces.size() / 3 == mesh.faces.size() / 3 - 2 * level.collapse_count);
    CHECK(level.kept_vertices.size() == mesh.vertex_count - level.collapse_count);
    CHECK(is_manifold(level));
  }
}

TEST_CASE("aqem is deterministic") {
  const OwnedAnimatedMesh mesh = animlod::testing::bending_tube(12, 10, 4, 1.2);
  AqemOptions options;
  options.target_ratios = {0.3};
  const AqemResult first = simplify(mesh, options);
  const AqemResult second = simplify(mesh, options);
  CHECK(first.levels[0].faces == second.levels[0].faces);
  CHECK(first.levels[0].positions == second.levels[0].positions);
  CHECK(first.collapses.removed == second.collapses.removed);
}

TEST_CASE("aqem over F identical frames equals aqem over one frame") {
  OwnedAnimatedMesh single = animlod::testing::bending_tube(12, 10, 4, 1.2);
  single.frames.resize(single.vertex_count * 3);
  single.frame_count = 1;
  OwnedAnimatedMesh repeated = single;
  for (int f = 1; f < 5; ++f) repeated.frames.insert(repeated.frames.end(), single.frames.begin(), single.frames.end());
  repeated.frame_count = 5;
  AqemOptions options;
  options.target_ratios = {0.5, 0.2};
  const AqemResult one = simplify(single, options);
  const AqemResult five = simplify(repeated, options);
  CHECK(one.collapses.removed == five.collapses.removed);
  CHECK(one.collapses.kept == five.collapses.kept);
  for (size_t i = 0; i < 2; ++i) {
    CHECK(one.levels[i].faces == five.levels[i].faces);
    const std::vector<float>& p = one.levels[i].positions;
    for (size_t f = 0; f < 5; ++f)
      for (size_t j = 0; j < p.size(); ++j) CHECK(five.levels[i].positions[f * p.size() + j] == doctest::Approx(p[j]));
    CHECK(five.levels[i].error == doctest::Approx(one.levels[i].error));
  }
}

TEST_CASE("aqem never flips a face of a deforming sphere in any frame") {
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(16, 24, 4);
  AqemOptions options;
  options.target_ratios = {0.05};
  const AqemResult result = simplify(mesh, options);
  CHECK(inward_faces(result.levels[0], mesh.frame_count) == 0);
}

TEST_CASE("aqem checks orientation in the frames outside the quadrics' frames too") {
  // Regression: with max_frames (or frame_subset) the frames left out of the quadrics get
  // kept + t (removed - kept) and went unchecked, so faces flipped there. Frame 1 jitters the
  // flat grid in its plane by under half a cell: no input face turns down, but collapses
  // placed from frame 0 alone flipped one. In-plane, every normal is +z or -z, so
  // fold_limit 0 (no flip in any single frame) must leave every face up.
  OwnedAnimatedMesh mesh = animlod::testing::grid(8);
  const size_t vertex_count = mesh.vertex_count;
  for (size_t v = 0; v < vertex_count; ++v) {
    const double i = double(v);
    const double offset[3] = {0.45 / 8 * std::sin(i * 6.8 + 0.3), 0.45 / 8 * std::sin(i * 9.2 + 1.1), 0.0};
    for (int k = 0; k < 3; ++k) mesh.frames.push_back(float(mesh.frames[3 * v + k] + offset[k]));
  }
  mesh.frame_count = 2;
  auto downward_faces = [](const std::vector<float>& positions, const std::vector<int32_t>& faces, size_t frame,
                           size_t vertex_count_) {
    size_t down = 0;
    const float* p = &positions[frame * vertex_count_ * 3];
    for (size_t t = 0; t < faces.size(); t += 3) {
      const float* a = p + 3 * faces[t];
      const float* b = p + 3 * faces[t + 1];
      const float* c = p + 3 * faces[t + 2];
      const double normal_z = double(b[0] - a[0]) * (c[1] - a[1]) - double(b[1] - a[1]) * (c[0] - a[0]);
      down += normal_z <= 0.0;
    }
    return down;
  };
  REQUIRE(downward_faces(mesh.frames, mesh.faces, 1, vertex_count) == 0);
  AqemOptions options;
  options.target_ratios = {0.5, 0.25, 0.1};
  options.max_frames = 1;
  options.fold_limit = 0.0;
  const AqemResult result = simplify(mesh, options);
  CHECK(result.frames_used == std::vector<int32_t>{0});
  for (const AqemLevel& level : result.levels)
    for (size_t frame = 0; frame < 2; ++frame)
      CHECK(downward_faces(level.positions, level.faces, frame, level.kept_vertices.size()) == 0);
}

TEST_CASE("aqem's collapse error is the RMS distance to the merged quadric's planes") {
  // Recomputes the first collapse's error from its definition: the planes of the faces around
  // the kept and the removed vertex (a face around both counts twice, as in Q_i + Q_j), the new
  // vertex's recorded positions, every frame (all are used). Closed mesh: no boundary planes.
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(8, 10, 3);
  AqemOptions options;
  options.target_ratios = {0.9};
  const AqemResult result = simplify(mesh, options);
  REQUIRE_FALSE(result.collapses.removed.empty());
  const int32_t ends[2] = {result.collapses.kept[0], result.collapses.removed[0]};
  double squared = 0.0;
  size_t planes = 0;
  for (size_t f = 0; f < mesh.frame_count; ++f) {
    const float* frame = &mesh.frames[f * mesh.vertex_count * 3];
    const float* placed = &result.collapses.positions[f * 3];
    for (int32_t end : ends)
      for (size_t t = 0; t < mesh.faces.size(); t += 3) {
        const int32_t* face = &mesh.faces[t];
        if (face[0] != end && face[1] != end && face[2] != end) continue;
        const float *a = frame + 3 * face[0], *b = frame + 3 * face[1], *c = frame + 3 * face[2];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        const double distance = (n[0] * (placed[0] - a[0]) + n[1] * (placed[1] - a[1]) + n[2] * (placed[2] - a[2])) /
                                std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        squared += distance * distance;
        ++planes;
      }
  }
  CHECK(result.collapses.error[0] == doctest::Approx(std::sqrt(squared / double(planes))).epsilon(1e-4));
  CHECK(result.collapses.error[0] > 0.0);
}

TEST_CASE("aqem keeps locked vertices where they are") {
  const OwnedAnimatedMesh mesh = animlod::testing::bending_tube(12, 10, 3, 1.0);
  std::vector<uint8_t> locked(mesh.vertex_count, 0);
  for (size_t v = 50; v < 60; ++v) locked[v] = 1;  // one ring in the middle
  AqemVertexData data;
  data.locked = locked.data();
  AqemOptions options;
  options.target_ratios = {0.2};
  const AqemResult result = simplify(mesh, options, data);
  const AqemLevel& level = result.levels[0];
  const size_t kept = level.kept_vertices.size();
  for (int32_t v = 50; v < 60; ++v) {
    const int32_t index = level.vertex_map[v];
    REQUIRE(index >= 0);
    CHECK(level.kept_vertices[index] == v);
    for (size_t f = 0; f < mesh.frame_count; ++f)
      for (int k = 0; k < 3; ++k)
        CHECK(level.positions[(f * kept + index) * 3 + k] == mesh.frames[(f * mesh.vertex_count + v) * 3 + k]);
  }
}

TEST_CASE("aqem stops at max_error and marks the levels it did not reach") {
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(12, 16, 2);
  AqemOptions options;
  options.target_ratios = {0.9, 0.05};
  const AqemResult unbounded = simplify(mesh, options);
  const double bound = unbounded.levels[0].error;
  REQUIRE(bound < unbounded.levels[1].error);
  options.max_error = bound;
  const AqemResult result = simplify(mesh, options);
  CHECK(result.levels[0].reached);
  CHECK_FALSE(result.levels[0].stopped_by_max_error);
  CHECK(result.levels[0].faces == unbounded.levels[0].faces);
  CHECK_FALSE(result.levels[1].reached);
  CHECK(result.levels[1].stopped_by_max_error);
  CHECK(result.levels[1].error <= bound);
  CHECK(result.levels[1].faces.size() / 3 > result.levels[1].target_face_count);
}

TEST_CASE("aqem says a level short of its target for want of a legal collapse is not max_error's") {
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(12, 16, 2);
  AqemOptions options;
  options.target_face_counts = {1};  // below any closed mesh's minimum
  options.max_error = 1e9;
  const AqemResult result = simplify(mesh, options);
  CHECK_FALSE(result.levels[0].reached);
  CHECK_FALSE(result.levels[0].stopped_by_max_error);
}

TEST_CASE("aqem samples frames that cover the motion") {
  const OwnedAnimatedMesh mesh = animlod::testing::bending_tube(8, 8, 9, 1.5);
  AqemOptions options;
  options.max_frames = 3;
  const AqemResult result = simplify(mesh, options);
  // Frame 0, then the farthest pose (the last), then the one farthest from both (the middle).
  CHECK(result.frames_used == std::vector<int32_t>{0, 4, 8});
  CHECK(result.levels[0].positions.size() == mesh.frame_count * result.levels[0].kept_vertices.size() * 3);
}

TEST_CASE("aqem merges skin weights and interpolates attributes") {
  const OwnedAnimatedMesh mesh = animlod::testing::grid(4);
  std::vector<int32_t> joints(mesh.vertex_count * 2);
  std::vector<float> weights(mesh.vertex_count * 2);
  std::vector<float> uvs(mesh.vertex_count * 2);
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    joints[2 * v] = int32_t(v % 3);
    joints[2 * v + 1] = 3;
    weights[2 * v] = 0.75f;
    weights[2 * v + 1] = 0.25f;
    uvs[2 * v] = mesh.frames[3 * v];
    uvs[2 * v + 1] = mesh.frames[3 * v + 1];
  }
  const AqemVertexData data = animlod::testing::uvs_and_two_influences(uvs, joints, weights);
  AqemOptions options;
  options.target_ratios = {0.25};
  const AqemResult result = simplify(mesh, options, data);
  const AqemLevel& level = result.levels[0];
  for (size_t i = 0; i < level.kept_vertices.size(); ++i) {
    CHECK(level.skin_weights[2 * i] + level.skin_weights[2 * i + 1] == doctest::Approx(1.0));
    CHECK(level.skin_weights[2 * i] >= level.skin_weights[2 * i + 1]);
    // UVs equal the flat grid's x, y, and vertices stay on the grid plane, so they agree.
    CHECK(level.attributes[2 * i] == doctest::Approx(level.positions[3 * i]).epsilon(1e-5));
    CHECK(level.attributes[2 * i + 1] == doctest::Approx(level.positions[3 * i + 1]).epsilon(1e-5));
  }
}

TEST_CASE("aqem names the element of bad input") {
  OwnedAnimatedMesh mesh = animlod::testing::grid(2);
  SUBCASE("non-finite position") {
    mesh.frames[3 * 4 + 1] = NAN;
    CHECK(failure(mesh) == "frame 0, vertex 4: non-finite position");
  }
  SUBCASE("index out of range") {
    mesh.faces[5] = 99;
    CHECK(failure(mesh).find("face 1 (0, 4, 99): vertex index 99 outside [0, 9)") == 0);
  }
  SUBCASE("every face degenerate") {
    std::fill(mesh.frames.begin(), mesh.frames.end(), 0.0f);
    CHECK(failure(mesh).find("faces: every face is degenerate") == 0);
  }
  SUBCASE("targets out of range") {
    AqemOptions options;
    options.target_face_counts = {9};
    CHECK(failure(mesh, options).find("target_face_counts: 9 outside [1, 8]") == 0);
    options.target_face_counts = {0};
    CHECK(failure(mesh, options).find("target_face_counts: 0 outside [1, M]") == 0);
    options.target_face_counts = {};
    options.target_ratios = {1.5};
    CHECK(failure(mesh, options).find("target_ratios: 1.5") == 0);
  }
}

TEST_CASE("aqem options that no mesh can take are refused without a mesh, and first") {
  AqemOptions options;
  CHECK(check_aqem_options(options).ok);
  SUBCASE("no level") {
    options.target_ratios = {};
    CHECK(check_aqem_options(options).message == "target_ratios: no level requested");
  }
  SUBCASE("a ratio outside (0, 1]") {
    options.target_ratios = {0.5, 0.0};
    CHECK(check_aqem_options(options).message.find("target_ratios: 0.0") == 0);
  }
  SUBCASE("a face count of 0, the ratios then unused") {
    options.target_ratios = {7.0};
    options.target_face_counts = {4, 0};
    CHECK(check_aqem_options(options).message.find("target_face_counts: 0 outside [1, M]") == 0);
    options.target_face_counts = {1000000};  // only a mesh can tell it is too many
    CHECK(check_aqem_options(options).ok);
  }
  SUBCASE("max_error") {
    options.max_error = -1.0;
    CHECK(check_aqem_options(options).message == "max_error: must be >= 0");
    options.max_error = NAN;
    CHECK(check_aqem_options(options).message == "max_error: must be >= 0");
  }
  SUBCASE("a negative frame") {
    options.frame_subset = {0, -2};
    CHECK(check_aqem_options(options).message == "frame_subset: frame -2 is negative");
  }
  SUBCASE("motion-feature options, only when the features are used") {
    options.motion_features.max_feature_weight = 0.5;
    CHECK(check_aqem_options(options).message.find("motion features: max_feature_weight") == 0);
    options.use_motion_features = false;
    CHECK(check_aqem_options(options).ok);
  }
  SUBCASE("before the mesh is read: a bad ratio on a bad mesh names the ratio") {
    OwnedAnimatedMesh mesh = animlod::testing::grid(2);
    mesh.frames[0] = NAN;
    options.target_ratios = {1.5};
    CHECK(failure(mesh, options).find("target_ratios: 1.5") == 0);
  }
}

TEST_CASE("aqem drops degenerate and repeated faces and counts them") {
  OwnedAnimatedMesh mesh = animlod::testing::grid(4);  // 32 faces
  mesh.faces.insert(mesh.faces.end(), {0, 0, 1});       // repeats a vertex
  mesh.faces.insert(mesh.faces.end(), {mesh.faces[3], mesh.faces[4], mesh.faces[5]});  // repeats face 1
  AqemOptions options;
  options.target_ratios = {1.0};
  const AqemResult result = simplify(mesh, options);
  CHECK(result.preparation.degenerate_faces == 1);
  CHECK(result.preparation.duplicate_faces == 1);
  CHECK(result.preparation.face_count == 32);
  CHECK(result.levels[0].faces.size() / 3 == 32);
}

TEST_CASE("aqem prepares a repeat in another turn, two-sided sheets and a fan of 100 triangles") {
  AqemOptions options;
  options.target_ratios = {1.0};
  OwnedAnimatedMesh mesh = animlod::testing::grid(4);  // 25 vertices, 32 faces
  SUBCASE("a repeated face, rotated") {
    mesh.faces.insert(mesh.faces.end(), {mesh.faces[7], mesh.faces[8], mesh.faces[6]});  // face 2
    const AqemResult result = simplify(mesh, options);
    CHECK(result.preparation.duplicate_faces == 1);
    CHECK(result.preparation.face_count == 32);
  }
  // A face and its turned-over copy (a two-sided sheet) share their edges: the copy leaves the
  // surface and comes back reversed on every level.
  SUBCASE("every face also turned over") {
    for (size_t f = 0; f < 32; ++f)
      mesh.faces.insert(mesh.faces.end(), {mesh.faces[3 * f], mesh.faces[3 * f + 2], mesh.faces[3 * f + 1]});
    const AqemResult result = simplify(mesh, options);
    CHECK(result.preparation.duplicate_faces == 0);
    CHECK(result.preparation.mirrored_faces == 32);
    CHECK(result.preparation.split_vertices == 0);
    CHECK(result.preparation.face_count == 32);
    CHECK(result.levels[0].faces.size() / 3 == 64);
  }
  SUBCASE("a disc of 100 triangles around one point, beside the grid") {  // its sides searched, not scanned
    const auto center = static_cast<int32_t>(mesh.vertex_count);
    mesh.frames.insert(mesh.frames.end(), {3.0f, 0.0f, 0.0f});
    for (int k = 0; k < 100; ++k) {
      const double angle = 2.0 * 3.14159265358979 * k / 100;
      mesh.frames.insert(mesh.frames.end(), {3.0f + static_cast<float>(std::cos(angle)),
                                             static_cast<float>(std::sin(angle)), 0.0f});
      mesh.faces.insert(mesh.faces.end(), {center, center + 1 + k, center + 1 + (k + 1) % 100});
    }
    mesh.vertex_count += 101;
    const AqemResult result = simplify(mesh, options);
    CHECK(result.preparation.split_vertices == 0);
    CHECK(result.preparation.face_count == 132);
    options.target_ratios = {0.5};
    CHECK(simplify(mesh, options).levels[0].faces.size() / 3 <= 66);
  }
  SUBCASE("a lone two-sided triangle beside the grid") {  // every directed edge still used once
    mesh.frames.insert(mesh.frames.end(), {2.0f, 0.0f, 0.0f, 3.0f, 0.0f, 0.0f, 2.0f, 1.0f, 0.0f});
    mesh.faces.insert(mesh.faces.end(), {25, 26, 27, 25, 27, 26});
    mesh.vertex_count += 3;
    const AqemResult result = simplify(mesh, options);
    CHECK(result.preparation.mirrored_faces == 1);
    CHECK(result.preparation.split_vertices == 0);
    CHECK(result.preparation.face_count == 33);
    CHECK(result.levels[0].faces.size() / 3 == 34);
  }
}

// Exporters write double-sided cloth and leaves as every face again in the reverse turn, on
// vertices of its own; cut apart and locked, such a sheet did not simplify at all.
TEST_CASE("aqem simplifies a two-sided sheet as its front and writes each level's faces back reversed") {
  const OwnedAnimatedMesh front = animlod::testing::grid(8);  // 81 vertices, 128 faces
  OwnedAnimatedMesh sheet = front;
  sheet.frames.insert(sheet.frames.end(), front.frames.begin(), front.frames.end());
  sheet.vertex_count *= 2;
  for (size_t f = 0; f < 128; ++f)
    for (size_t c : {0, 2, 1}) sheet.faces.push_back(front.faces[3 * f + c] + 81);
  AqemOptions options;
  options.target_ratios = {0.5, 0.25, 0.1};
  const AqemResult one = simplify(front, options), two = simplify(sheet, options);
  CHECK(two.preparation.mirrored_faces == 128);
  CHECK(two.preparation.split_vertices == 0);
  REQUIRE(two.levels.size() == one.levels.size());
  for (size_t l = 0; l < one.levels.size(); ++l) {
    const AqemLevel &a = one.levels[l], &b = two.levels[l];
    const size_t m = a.faces.size() / 3;
    REQUIRE(b.faces.size() == 6 * m);
    CHECK(b.target_face_count == a.target_face_count + m);  // the surface's target and the mirrors
    CHECK(b.kept_vertices == a.kept_vertices);
    CHECK(b.positions == a.positions);
    for (size_t v = 0; v < 81; ++v) {  // the back's own vertices map where the front's do
      CHECK(b.vertex_map[v] == a.vertex_map[v]);
      CHECK(b.vertex_map[v + 81] == a.vertex_map[v]);
    }
    for (size_t f = 0; f < m; ++f) {
      CHECK(b.face_sources[f] == a.face_sources[f]);
      CHECK(b.face_sources[m + f] == a.face_sources[f] + 128);  // the reversed copy's own input face
      for (size_t c = 0; c < 3; ++c) {
        CHECK(b.faces[3 * f + c] == a.faces[3 * f + c]);
        CHECK(b.faces[3 * (m + f) + c] == a.faces[3 * f + (3 - c) % 3]);  // corners 0, 2, 1
      }
    }
  }
}

TEST_CASE("aqem simplifies a bow tie and a three-face edge, keeping the spots stitched") {
  // Two grids sharing only their corner vertex 24 (a bow tie), plus a fin on edge (0, 1) of
  // the first grid (an edge of three faces).
  OwnedAnimatedMesh mesh = animlod::testing::grid(4);  // 25 vertices, 32 faces, in z = 0
  const OwnedAnimatedMesh other = animlod::testing::grid(4);
  const auto base = static_cast<int32_t>(mesh.vertex_count);
  for (size_t v = 0; v < other.vertex_count; ++v)  // the second grid from (1, 1) on, tilted up
    mesh.frames.insert(mesh.frames.end(), {1.0f + other.frames[3 * v], 1.0f + other.frames[3 * v + 1],
                                           0.5f * other.frames[3 * v]});
  mesh.vertex_count += other.vertex_count;
  for (int32_t index : other.faces) mesh.faces.push_back(index == 0 ? 24 : base + index);
  mesh.frames.insert(mesh.frames.end(), {0.1f, 0.0f, 0.5f});  // the fin's tip
  mesh.faces.insert(mesh.faces.end(), {0, 1, static_cast<int32_t>(mesh.vertex_count)});
  mesh.vertex_count += 1;
  AqemOptions options;
  options.target_ratios = {0.3};
  const AqemResult result = simplify(mesh, options);
  CHECK(result.preparation.split_vertices >= 1);
  const AqemLevel& level = result.levels[0];
  CHECK(level.faces.size() / 3 < mesh.faces.size() / 3);
  CHECK(is_manifold(level) == false);  // the output keeps the input's non-manifold spots...
  // ... and the vertices at those spots stay where they were: the pieces are not torn apart.
  for (int32_t spot : {0, 1, 24}) {
    const int32_t out = level.vertex_map[spot];
    REQUIRE(out >= 0);
    for (int axis = 0; axis < 3; ++axis) CHECK(level.positions[3 * out + axis] == mesh.frames[3 * spot + axis]);
  }
}

TEST_CASE("aqem welds seam copies and keeps the seam") {
  // A grid cut along x = 0.5 into two UV charts: the copies of the seam vertices carry different
  // UVs. Welded, the grid simplifies as one surface; the seam survives with its two UV sides.
  const int n = 8;
  std::vector<float> uvs;
  const OwnedAnimatedMesh mesh = animlod::testing::grid_with_uv_seam(n, uvs);
  AqemVertexData data;
  data.attributes = uvs.data();
  data.attribute_count = 2;
  AqemOptions options;
  options.target_ratios = {0.25};
  const AqemResult result = simplify(mesh, options, data);
  CHECK(result.preparation.welded_vertices == size_t(n + 1));
  CHECK(result.preparation.seam_vertices == size_t(n + 1));
  const AqemLevel& level = result.levels[0];
  CHECK(level.reached);
  animlod::testing::check_uv_seam_kept(level);
}

TEST_CASE("aqem keeps a point where three or more attribute charts meet in place") {
  // An open cone whose sides form three UV charts meeting at the apex. A rim vertex on a seam
  // may collapse along its seam into the apex, but the apex must not move, as meshoptimizer's
  // "complex" vertices do not: moved, it would drag every chart's corner (here down towards the
  // rim, shortening the cone: the merged quadric's optimum).
  const int sides = 9;
  const double pi = 3.14159265358979323846;
  OwnedAnimatedMesh mesh;
  mesh.frame_count = 1;
  std::vector<float> uvs;
  // Apex copies first, one per chart, so that the apex is the kept end of its edges.
  for (int chart = 0; chart < 3; ++chart) {
    mesh.frames.insert(mesh.frames.end(), {0.0f, 0.0f, 2.0f});
    uvs.insert(uvs.end(), {10.0f * chart, 1.0f});
  }
  // Rim vertices, one copy per chart that uses them.
  std::vector<std::array<int32_t, 3>> rim(sides, {-1, -1, -1});
  auto rim_vertex = [&](int i, int chart) {
    int32_t& v = rim[i % sides][chart];
    if (v < 0) {
      v = static_cast<int32_t>(mesh.frames.size() / 3);
      const double angle = 2 * pi * (i % sides) / sides;
      mesh.frames.insert(mesh.frames.end(), {float(std::cos(angle)), float(std::sin(angle)), 0.0f});
      uvs.insert(uvs.end(), {10.0f * chart + float(i % sides), 0.0f});
    }
    return v;
  };
  for (int i = 0; i < sides; ++i) {
    const int chart = i / 3;
    mesh.faces.insert(mesh.faces.end(), {rim_vertex(i, chart), rim_vertex(i + 1, chart), chart});
  }
  mesh.vertex_count = mesh.frames.size() / 3;
  // Only the apex and the rim seam point between charts 0 and 1 may move; that rim point can
  // only collapse along its seam, into the apex.
  std::vector<uint8_t> locked(mesh.vertex_count, 1);
  for (int32_t v : {0, 1, 2, rim[3][0], rim[3][1]}) locked[v] = 0;
  AqemVertexData data;
  data.attributes = uvs.data();
  data.attribute_count = 2;
  data.locked = locked.data();
  AqemOptions options;
  options.target_face_counts = {7};
  const AqemResult result = simplify(mesh, options, data);
  CHECK(result.preparation.seam_vertices == 4);  // the apex and the three rim seam points
  const AqemLevel& level = result.levels[0];
  CHECK(level.reached);
  for (int32_t copy = 0; copy < 3; ++copy) {
    const int32_t out = level.vertex_map[copy];
    REQUIRE(out >= 0);
    CHECK(level.positions[3 * out] == 0.0f);
    CHECK(level.positions[3 * out + 1] == 0.0f);
    CHECK(level.positions[3 * out + 2] == 2.0f);
  }
}

TEST_CASE("aqem keeps guarded vertices while other collapses remain, then frees them") {
  // A sphere with every fifth vertex guarded: at half the faces the others can give way, so the
  // guarded ones stay where they were; far below what the others can give, they must go too.
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(8, 10, 2);  // 72 vertices, 140 faces
  std::vector<uint8_t> guarded(mesh.vertex_count, 0);
  for (size_t v = 0; v < mesh.vertex_count; v += 5) guarded[v] = 1;
  auto guarded_kept = [&](const AqemResult& result, size_t level_index) {
    const AqemLevel& level = result.levels[level_index];
    size_t kept = 0;
    for (size_t v = 0; v < mesh.vertex_count; ++v) {
      if (!guarded[v]) continue;
      const int32_t out = level.vertex_map[v];
      bool same = level.kept_vertices[out] == static_cast<int32_t>(v);
      for (int axis = 0; axis < 3; ++axis) same &= level.positions[3 * out + axis] == mesh.frames[3 * v + axis];
      kept += same;
    }
    return kept;
  };
  const size_t guarded_count = static_cast<size_t>(std::count(guarded.begin(), guarded.end(), 1));
  AqemOptions options;
  options.target_face_counts = {70, 8};
  AqemVertexData data;
  data.guarded = guarded.data();
  const AqemResult with_guards = simplify(mesh, options, data);
  CHECK(guarded_kept(with_guards, 0) == guarded_count);
  CHECK(with_guards.levels[1].reached);
  CHECK(guarded_kept(with_guards, 1) < guarded_count);
  const AqemResult control = simplify(mesh, options);  // the same run without guards moves some
  CHECK(guarded_kept(control, 0) < guarded_count);
}

TEST_CASE("aqem simplifies an unwelded (flat-shaded) mesh like the welded one") {
  const OwnedAnimatedMesh welded = animlod::testing::sphere(8, 10, 2);
  OwnedAnimatedMesh unwelded;
  unwelded.frame_count = welded.frame_count;
  const size_t corners = welded.faces.size();
  unwelded.vertex_count = corners;
  for (size_t f = 0; f < welded.frame_count; ++f)
    for (size_t c = 0; c < corners; ++c) {
      const float* p = &welded.frames[(f * welded.vertex_count + welded.faces[c]) * 3];
      unwelded.frames.insert(unwelded.frames.end(), {p[0], p[1], p[2]});
    }
  for (size_t c = 0; c < corners; ++c) unwelded.faces.push_back(static_cast<int32_t>(c));
  AqemOptions options;
  options.target_ratios = {0.5, 0.1};
  const AqemResult a = simplify(welded, options), b = simplify(unwelded, options);
  CHECK(b.preparation.welded_vertices == corners - welded.vertex_count);
  for (size_t l = 0; l < 2; ++l) {
    CHECK(a.levels[l].reached);
    CHECK(b.levels[l].reached);
    CHECK(b.levels[l].faces.size() == a.levels[l].faces.size());
  }
}

TEST_CASE("aqem stops at the smallest reachable level and says so") {
  // A closed surface cannot go below a tetrahedron's four faces.
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(8, 10, 2);
  AqemOptions options;
  options.target_face_counts = {100, 1};
  const AqemResult result = simplify(mesh, options);
  CHECK(result.levels[0].reached);
  CHECK_FALSE(result.levels[1].reached);
  CHECK(result.levels[1].faces.size() / 3 >= 4);
  CHECK(result.levels[1].faces.size() / 3 < 100);
}

TEST_CASE("aqem rejects per-vertex data whose pointers and counts disagree") {
  const OwnedAnimatedMesh mesh = animlod::testing::grid(2);
  std::vector<int32_t> joints(mesh.vertex_count, 0);
  std::vector<float> weights(mesh.vertex_count, 1.0f);
  AqemVertexData data;
  std::string expected;
  SUBCASE("attribute_count without attributes") {
    data.attribute_count = 2;
    expected = "attributes: attribute_count is 2 but attributes is null";
  }
  SUBCASE("skin_joints without skin_weights") {
    data.skin_joints = joints.data();
    data.influence_count = 1;
    expected = "skin_joints and skin_weights: give both or neither";
  }
  SUBCASE("skin_weights without skin_joints") {
    data.skin_weights = weights.data();
    data.influence_count = 1;
    expected = "skin_joints and skin_weights: give both or neither";
  }
  AqemResult result;
  const animlod::Status status = simplify_animated(mesh.view(), data, AqemOptions{}, result);
  CHECK_FALSE(status.ok);
  CHECK(status.message == expected);
}

TEST_CASE("aqem leaves the result empty when it fails") {
  // Regression: frames_used was written before later checks failed, and a throwing progress
  // callback left the levels taken so far.
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(8, 10, 2);
  AqemResult result;
  result.frames_used = {7};  // stale content must go too
  AqemOptions options;
  options.target_ratios = {0.9, 0.5};
  SUBCASE("bad vertex data") {
    const std::vector<float> importance(mesh.vertex_count, -1.0f);
    AqemVertexData data;
    data.importance = importance.data();
    CHECK_FALSE(simplify_animated(mesh.view(), data, options, result).ok);
  }
  SUBCASE("progress callback throws") {
    options.target_ratios = {1.0, 0.5};  // the first level is taken before the first call
    options.progress = [](size_t, size_t) { throw std::runtime_error("cancelled"); };
    CHECK_THROWS_AS(simplify_animated(mesh.view(), {}, options, result), std::runtime_error);
  }
  CHECK(result.levels.empty());
  CHECK(result.frames_used.empty());
  CHECK(result.collapses.removed.empty());
  CHECK(result.vertex_weights.empty());
}

TEST_CASE("aqem reduces a subdivided cube to its eight exact corners") {
  const OwnedAnimatedMesh mesh = animlod::testing::subdivided_cube(4);  // 192 faces
  AqemOptions options;
  options.target_face_counts = {12};
  const AqemResult result = simplify(mesh, options);
  const AqemLevel& level = result.levels[0];
  CHECK(level.reached);
  CHECK(level.faces.size() / 3 == 12);
  CHECK(level.error == doctest::Approx(0.0));
  REQUIRE(level.kept_vertices.size() == 8);
  std::set<std::array<float, 3>> corners;
  for (size_t i = 0; i < 8; ++i)
    corners.insert({std::round(level.positions[3 * i] * 1e5f) / 1e5f, std::round(level.positions[3 * i + 1] * 1e5f) / 1e5f,
                    std::round(level.positions[3 * i + 2] * 1e5f) / 1e5f});
  CHECK(corners.size() == 8);
  for (const auto& corner : corners)
    for (float value : corner) CHECK((value == 0.0f || value == 1.0f));
}

TEST_CASE("amplitude weights that find no feature leave the collapse order of features off, bit for bit") {
  // Capture-like noise on a still sphere: the paper's rule makes features of the noise (and so
  // a different order, the control); the default weighting finds nothing and changes nothing.
  const OwnedAnimatedMesh mesh = animlod::testing::jittering_sphere(16, 24, 12, 0.01f);
  AqemOptions options;
  options.target_ratios = {0.5, 0.1};
  const AqemResult weighted = simplify(mesh, options);
  options.use_motion_features = false;
  const AqemResult plain = simplify(mesh, options);
  for (float w : weighted.vertex_weights) CHECK(w == 1.0f);
  CHECK(weighted.collapses.removed == plain.collapses.removed);
  CHECK(weighted.collapses.kept == plain.collapses.kept);
  CHECK(weighted.collapses.positions == plain.collapses.positions);
  CHECK(weighted.collapses.cost == plain.collapses.cost);
  options.use_motion_features = true;
  options.motion_features.feature_weighting = animlod::FeatureWeighting::paper;
  const AqemResult paper = simplify(mesh, options);
  CHECK(paper.collapses.removed != plain.collapses.removed);
}
