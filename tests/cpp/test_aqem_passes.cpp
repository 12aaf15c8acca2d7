// AQEM's collapse passes (meshoptimizer's scheme, collapse_engine.cpp run_passes) on meshes
// large enough to use them (more than EngineOptions::passes_above_edges = 100k edges; smaller
// meshes run the greedy order, which test_aqem.cpp covers), and the quadric's 3x3 solve.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "animlod/aqem.hpp"
#include "quadric.hpp"
#include "aqem_level_checks.hpp"
#include "test_aqem_meshes.hpp"

using animlod::AqemLevel;
using animlod::AqemOptions;
using animlod::AqemResult;
using animlod::AqemVertexData;
using animlod::testing::OwnedAnimatedMesh;
using animlod::testing::inward_faces;
using animlod::testing::is_manifold;
using animlod::testing::simplify;

namespace {

size_t edge_count(const OwnedAnimatedMesh& mesh) {
  std::set<std::pair<int32_t, int32_t>> edges;
  for (size_t f = 0; f < mesh.faces.size(); f += 3)
    for (int k = 0; k < 3; ++k) {
      const int32_t a = mesh.faces[f + k], b = mesh.faces[f + (k + 1) % 3];
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  return edges.size();
}

}  // namespace

TEST_CASE("collapse passes reach every level without flipping a face in any frame") {
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(200, 340, 2);  // 135,320 faces
  REQUIRE(edge_count(mesh) > 100000);  // passes run
  AqemOptions options;
  options.target_ratios = {0.5, 0.2, 0.05};
  const AqemResult result = simplify(mesh, options);
  REQUIRE(result.levels.size() == 3);
  double previous_error = 0.0;
  for (const AqemLevel& level : result.levels) {
    CHECK(level.reached);
    CHECK(level.faces.size() / 3 <= level.target_face_count);
    CHECK(level.faces.size() / 3 + 2 > level.target_face_count);  // a collapse removes at most two
    CHECK(is_manifold(level));
    CHECK(inward_faces(level, mesh.frame_count) == 0);
    CHECK(level.error >= previous_error);
    previous_error = level.error;
  }
  // The record replays the levels: level i is its first collapse_count collapses.
  CHECK(result.collapses.removed.size() == result.levels.back().collapse_count);
}

TEST_CASE("collapse passes are deterministic") {
  const OwnedAnimatedMesh mesh = animlod::testing::jittering_sphere(200, 340, 2, 0.02f);
  REQUIRE(edge_count(mesh) > 100000);
  AqemOptions options;
  options.target_ratios = {0.1};
  const AqemResult first = simplify(mesh, options), second = simplify(mesh, options);
  CHECK(first.levels[0].faces == second.levels[0].faces);
  CHECK(first.levels[0].positions == second.levels[0].positions);
  CHECK(first.collapses.cost == second.collapses.cost);
}

TEST_CASE("collapse passes on two workers keep seams and carry attributes and skin weights") {
  // Passes perform their chosen collapses on two workers, one per half of the mesh, and leave
  // those near the other half to one thread afterwards (collapse_engine.cpp perform_in_halves):
  // wedges, UVs and weights must cross over as they do one collapse at a time.
  std::vector<float> uvs;
  const OwnedAnimatedMesh mesh = animlod::testing::grid_with_uv_seam(240, uvs);  // 115,200 faces
  REQUIRE(edge_count(mesh) > 100000);
  std::vector<int32_t> joints(mesh.vertex_count * 2);
  std::vector<float> weights(mesh.vertex_count * 2);
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    joints[2 * v] = mesh.frames[3 * v + 1] < 0.5f ? 0 : 1;
    joints[2 * v + 1] = 2;
    weights[2 * v] = 0.75f;
    weights[2 * v + 1] = 0.25f;
  }
  const AqemVertexData data = animlod::testing::uvs_and_two_influences(uvs, joints, weights);
  AqemOptions options;
  options.target_ratios = {0.1};
  const AqemResult result = simplify(mesh, options, data);
  const AqemLevel& level = result.levels[0];
  REQUIRE(level.reached);
  CHECK(is_manifold(level));
  animlod::testing::check_uv_seam_kept(level);
  for (size_t i = 0; i < level.kept_vertices.size(); ++i) {
    // UVs are x, y (10 over on the right chart) and the grid stays flat, so they agree.
    const float u = level.attributes[2 * i] > 5.0f ? level.attributes[2 * i] - 10.0f : level.attributes[2 * i];
    CHECK(u == doctest::Approx(level.positions[3 * i]).epsilon(1e-5));
    CHECK(level.attributes[2 * i + 1] == doctest::Approx(level.positions[3 * i + 1]).epsilon(1e-5));
    float sum = 0.0f;
    for (int k = 0; k < 2; ++k) sum += level.skin_weights[2 * i + k];
    CHECK(sum == doctest::Approx(1.0));
  }
  const AqemResult again = simplify(mesh, options, data);
  CHECK(again.levels[0].faces == level.faces);
  CHECK(again.levels[0].attributes == level.attributes);
  CHECK(again.levels[0].skin_weights == level.skin_weights);
}

TEST_CASE("collapse passes keep guarded vertices while other collapses remain, then free them") {
  const OwnedAnimatedMesh mesh = animlod::testing::sphere(200, 340, 1);
  REQUIRE(edge_count(mesh) > 100000);
  std::vector<uint8_t> guarded(mesh.vertex_count, 0);
  for (size_t v = 0; v < mesh.vertex_count; v += 5) guarded[v] = 1;
  const size_t guarded_count = static_cast<size_t>(std::count(guarded.begin(), guarded.end(), 1));
  auto guarded_kept = [&](const AqemLevel& level) {
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
  AqemOptions options;
  options.target_face_counts = {mesh.faces.size() / 3 / 2, 16};
  AqemVertexData data;
  data.guarded = guarded.data();
  const AqemResult result = simplify(mesh, options, data);
  CHECK(guarded_kept(result.levels[0]) == guarded_count);
  CHECK(result.levels[1].reached);
  CHECK(guarded_kept(result.levels[1]) < guarded_count);
}

TEST_CASE("collapse passes stop at max_error like the greedy order") {
  const OwnedAnimatedMesh mesh = animlod::testing::jittering_sphere(200, 340, 1, 0.02f);
  AqemOptions options;
  options.target_ratios = {0.8, 0.05};
  const AqemResult unbounded = simplify(mesh, options);
  const double bound = unbounded.levels[0].error;
  REQUIRE(bound < unbounded.levels[1].error);
  options.max_error = bound;
  const AqemResult result = simplify(mesh, options);
  CHECK(result.levels[0].reached);
  CHECK_FALSE(result.levels[1].reached);
  CHECK(result.levels[1].stopped_by_max_error);
  CHECK(result.levels[1].error <= bound);
  for (double error : result.collapses.error) CHECK(error <= bound);
}

TEST_CASE("merged minimisers solve A v = b frame by frame and refuse a singular A") {
  using animlod::detail::Quadric;
  std::mt19937 random(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  // Frames 0-199: two random planes in the kept quadric, two in the removed one (A is almost
  // surely regular); 200: two planes meeting in a line (every point of it is a minimiser);
  // 201: no plane at all; 202: a non-finite coefficient.
  constexpr size_t kRandom = 200, kFrames = kRandom + 3;
  std::vector<Quadric> kept(kFrames), removed(kFrames);
  auto random_plane = [&]() {
    const Eigen::Vector3d normal = Eigen::Vector3d(uniform(random), uniform(random), uniform(random)).normalized();
    return Quadric::plane(normal, Eigen::Vector3d(uniform(random), uniform(random), 0.0), 1.0);
  };
  for (size_t k = 0; k < kRandom; ++k) {
    kept[k] = random_plane() + random_plane();
    removed[k] = random_plane() + random_plane();
  }
  kept[kRandom] = Quadric::plane(Eigen::Vector3d::UnitX(), Eigen::Vector3d::Zero(), 1.0);
  removed[kRandom] = Quadric::plane(Eigen::Vector3d::UnitY(), Eigen::Vector3d::Zero(), 1.0);
  kept[kRandom + 2] = random_plane();
  kept[kRandom + 2].b1 = std::numeric_limits<double>::infinity();
  animlod::detail::MergedMinimizers minimizers;
  minimizers.solve(kept.data(), removed.data(), kFrames);
  size_t regular = 0;
  for (size_t k = 0; k < kRandom; ++k) {
    const Quadric q = kept[k] + removed[k];
    Eigen::Matrix3d a;
    a << q.a00, q.a01, q.a02, q.a01, q.a11, q.a12, q.a02, q.a12, q.a22;
    const Eigen::Vector3d b(q.b0, q.b1, q.b2);
    if (std::abs(a.determinant()) <= 1e-6) continue;
    ++regular;
    REQUIRE(minimizers.solved(k));
    const Eigen::Vector3d v = minimizers.position(k);
    CHECK((a * v - b).norm() <= 1e-9 * (1.0 + b.norm()) * a.norm() / std::abs(a.determinant()));
    CHECK((v - a.lu().solve(b)).norm() <= 1e-8 * (1.0 + v.norm()));
    CHECK(minimizers.value(k) == q.evaluate(v));
  }
  CHECK(regular > kRandom / 2);
  CHECK_FALSE(minimizers.solved(kRandom));
  CHECK_FALSE(minimizers.solved(kRandom + 1));
  CHECK_FALSE(minimizers.solved(kRandom + 2));
  // One frame goes its own way (no columns): the same bits as the same frame among many.
  std::vector<Eigen::Vector3d> positions(kFrames);
  std::vector<double> values(kFrames);
  std::vector<bool> solved(kFrames);
  for (size_t k = 0; k < kFrames; ++k)
    positions[k] = minimizers.position(k), values[k] = minimizers.value(k), solved[k] = minimizers.solved(k);
  for (size_t k = 0; k < kFrames; ++k) {
    minimizers.solve(kept.data() + k, removed.data() + k, 1);
    CHECK(minimizers.solved(0) == solved[k]);
    if (!solved[k]) continue;
    CHECK(minimizers.position(0) == positions[k]);
    CHECK(minimizers.value(0) == values[k]);
  }
  // Fewer frames in the same object: the columns are laid out for the new count.
  minimizers.solve(kept.data() + kRandom, removed.data() + kRandom, 2);
  CHECK_FALSE(minimizers.solved(0));
  minimizers.solve(kept.data() + kRandom - 1, removed.data() + kRandom - 1, 1);
  CHECK(minimizers.solved(0));
  CHECK(minimizers.value(0) == (kept[kRandom - 1] + removed[kRandom - 1]).evaluate(minimizers.position(0)));
}
