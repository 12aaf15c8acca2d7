#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "animlod/point_mesh_distance.hpp"

namespace {

using Vec3 = std::array<double, 3>;

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

double segment_distance2(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = sub(b, a);
  const double t = dot(ab, ab) > 0.0 ? std::clamp(dot(sub(p, a), ab) / dot(ab, ab), 0.0, 1.0) : 0.0;
  const Vec3 q{a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]};
  return dot(sub(p, q), sub(p, q));
}

// An independent formulation: the plane distance when the projection falls inside (all three
// edge normals agree), else the nearest of the three edges.
double brute_force(const std::vector<double>& v, const std::vector<int32_t>& f, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < f.size() / 3; ++t) {
    std::array<Vec3, 3> c;
    for (int k = 0; k < 3; ++k) c[k] = {v[3 * f[3 * t + k]], v[3 * f[3 * t + k] + 1], v[3 * f[3 * t + k] + 2]};
    const Vec3 n = cross(sub(c[1], c[0]), sub(c[2], c[0]));
    bool inside = dot(n, n) > 1e-24;
    for (int k = 0; k < 3 && inside; ++k) inside = dot(cross(sub(c[(k + 1) % 3], c[k]), sub(p, c[k])), n) >= 0.0;
    double d2 = std::min({segment_distance2(p, c[0], c[1]), segment_distance2(p, c[1], c[2]), segment_distance2(p, c[2], c[0])});
    if (inside) d2 = std::min(d2, dot(sub(p, c[0]), n) * dot(sub(p, c[0]), n) / dot(n, n));
    best = std::min(best, d2);
  }
  return best;
}

animlod::TriangleMeshView view(const std::vector<double>& v, const std::vector<int32_t>& f) {
  return {v.data(), f.data(), v.size() / 3, f.size() / 3};
}

}  // namespace

TEST_CASE("point_mesh_squared_distance matches brute force, degenerate triangles included") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> v;
  for (int i = 0; i < 300; ++i) v.push_back(uniform(rng));
  std::vector<int32_t> f;
  std::uniform_int_distribution<int32_t> pick(0, 99);
  for (int t = 0; t < 500; ++t)
    for (int k = 0; k < 3; ++k) f.push_back(pick(rng));
  f.insert(f.end(), {0, 0, 0, 1, 2, 1});  // a point and a segment
  v.insert(v.end(), {0, 0, 0, 1, 1, 1, 2, 2, 2});  // three collinear vertices, 100..102
  f.insert(f.end(), {100, 101, 102});
  std::vector<double> points;
  for (int i = 0; i < 3 * 5000; ++i) points.push_back(2.0 * uniform(rng));
  points.insert(points.end(), {v[0], v[1], v[2], 1.5, 1.5, 1.5});  // on a vertex, on the segment
  const size_t count = points.size() / 3;
  std::vector<double> one(count), two(count);
  REQUIRE(animlod::point_mesh_squared_distance(view(v, f), points.data(), count, 1, one.data()));
  REQUIRE(animlod::point_mesh_squared_distance(view(v, f), points.data(), count, 2, two.data()));
  CHECK(one == two);  // the thread count does not change a bit
  for (size_t i = 0; i < count; ++i) {
    const double expected = brute_force(v, f, {points[3 * i], points[3 * i + 1], points[3 * i + 2]});
    REQUIRE(one[i] == doctest::Approx(expected).epsilon(1e-9).scale(1e-12));
  }
  CHECK(one[count - 2] == 0.0);
  CHECK(one[count - 1] == doctest::Approx(0.0).scale(1e-12));
}

TEST_CASE("point_mesh_squared_distance names bad input") {
  const std::vector<double> v{0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::vector<int32_t> f{0, 1, 3};
  const std::vector<double> p{0, 0, 1};
  double out = 0.0;
  auto status = animlod::point_mesh_squared_distance(view(v, f), p.data(), 1, 0, &out);
  CHECK_FALSE(status);
  CHECK(status.message.find("faces[0]") != std::string::npos);
  status = animlod::point_mesh_squared_distance(view(v, {}), p.data(), 1, 0, &out);
  CHECK(status.message.find("no triangle") != std::string::npos);
  const std::vector<double> nan_point{0, std::nan(""), 0};
  status = animlod::point_mesh_squared_distance(view(v, {0, 1, 2}), nan_point.data(), 1, 0, &out);
  CHECK(status.message.find("points[0]") != std::string::npos);
}

TEST_CASE("point_mesh_squared_distance refits the first frame's tree to the others") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> first;
  for (int i = 0; i < 3 * 200; ++i) first.push_back(uniform(rng));
  std::vector<int32_t> f;
  std::uniform_int_distribution<int32_t> pick(0, 199);
  for (int t = 0; t < 3 * 300; ++t) f.push_back(pick(rng));
  // Frame 1 moves every vertex far (the first frame's tree no longer fits it at all).
  std::vector<double> both = first;
  for (double x : first) both.push_back(3.0 * x * x - 1.0);
  std::vector<double> points;
  for (int i = 0; i < 3 * 2 * 3000; ++i) points.push_back(2.0 * uniform(rng));
  animlod::TriangleMeshView mesh{both.data(), f.data(), 200, 300, 2};
  std::vector<double> out(2 * 3000);
  REQUIRE(animlod::point_mesh_squared_distance(mesh, points.data(), 3000, 0, out.data()));
  const std::vector<double> second(both.begin() + 600, both.end());
  for (size_t i = 0; i < 3000; ++i) {
    REQUIRE(out[i] == doctest::Approx(brute_force(first, f, {points[3 * i], points[3 * i + 1], points[3 * i + 2]}))
                          .epsilon(1e-9)
                          .scale(1e-12));
    const size_t j = 3000 + i;
    REQUIRE(out[j] == doctest::Approx(brute_force(second, f, {points[3 * j], points[3 * j + 1], points[3 * j + 2]}))
                          .epsilon(1e-9)
                          .scale(1e-12));
  }
  both[600 + 4] = std::nan("");
  const auto status = animlod::point_mesh_squared_distance(mesh, points.data(), 3000, 0, out.data());
  CHECK(status.message.find("vertices[1, 1]") != std::string::npos);
}

TEST_CASE("point_mesh_max_squared_distance is the largest of every distance, to the bit") {
  // A random soup in three frames, each moving every vertex; points near the surface and far.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const size_t vertex_count = 300, point_count = 6000, frames = 3;
  std::vector<double> vertices;
  for (size_t i = 0; i < 3 * vertex_count; ++i) vertices.push_back(uniform(rng));
  for (size_t frame = 1; frame < frames; ++frame)
    for (size_t i = 0; i < 3 * vertex_count; ++i) vertices.push_back(vertices[i] + 0.2 * frame * uniform(rng));
  std::vector<int32_t> f;
  std::uniform_int_distribution<int32_t> pick(0, static_cast<int32_t>(vertex_count) - 1);
  for (int t = 0; t < 3 * 400; ++t) f.push_back(pick(rng));
  std::vector<double> points;
  for (size_t i = 0; i < 3 * point_count * frames; ++i) points.push_back((i % 7 == 0 ? 3.0 : 1.2) * uniform(rng));
  const animlod::TriangleMeshView mesh{vertices.data(), f.data(), vertex_count, f.size() / 3, frames};
  std::vector<double> every(point_count * frames);
  REQUIRE(animlod::point_mesh_squared_distance(mesh, points.data(), point_count, 1, every.data()));
  const double largest = *std::max_element(every.begin(), every.end());
  for (const unsigned threads : {1u, 2u})
    for (const double floor : {0.0, 0.25 * largest, 0.999 * largest, largest, 2.0 * largest}) {
      double out = -1.0;
      REQUIRE(animlod::point_mesh_max_squared_distance(mesh, points.data(), point_count, threads, floor, out));
      CHECK(out == std::max(floor, largest));
    }
  double out = 0.0;
  const std::vector<double> nan_point{0, std::nan(""), 0};
  const auto status = animlod::point_mesh_max_squared_distance(view(vertices, {0, 1, 2}), nan_point.data(), 1, 0,
                                                               0.0, out);
  CHECK(status.message.find("points[0]") != std::string::npos);
  CHECK(animlod::point_mesh_max_squared_distance(mesh, points.data(), point_count, 0, std::nan(""), out).message ==
        "floor: not a number");

  // Segments (an empty one among them, ends inside the threads' blocks of points): each the
  // largest of its own points' distances or its floor, to the bit.
  const std::vector<size_t> ends{1000, 1000, 3333, 3334, point_count};
  const std::vector<double> floors{0.0, 0.5, 0.1 * largest, 0.0, 0.9 * largest};
  for (const unsigned threads : {1u, 2u}) {
    std::vector<double> per_segment(ends.size(), -1.0);
    REQUIRE(animlod::point_mesh_max_squared_distances(mesh, points.data(), point_count, ends.data(), ends.size(),
                                                      threads, floors.data(), per_segment.data()));
    for (size_t s = 0; s < ends.size(); ++s) {
      double expected = floors[s];
      for (size_t frame = 0; frame < frames; ++frame)
        for (size_t i = s ? ends[s - 1] : 0; i < ends[s]; ++i)
          expected = std::max(expected, every[frame * point_count + i]);
      CHECK(per_segment[s] == expected);
    }
  }
  // Per frame: each frame's largest to the bit, on one thread and two.
  for (const unsigned threads : {1u, 2u}) {
    std::vector<double> per_frame(frames, -1.0);
    REQUIRE(animlod::point_mesh_frame_max_squared_distances(mesh, points.data(), point_count, threads,
                                                             per_frame.data()));
    for (size_t frame = 0; frame < frames; ++frame)
      CHECK(per_frame[frame] == *std::max_element(every.begin() + static_cast<long>(frame * point_count),
                                                  every.begin() + static_cast<long>((frame + 1) * point_count)));
  }
  const std::vector<size_t> short_ends{1000, point_count - 1}, falling{1000, 999, point_count};
  std::vector<double> scratch(ends.size());
  CHECK(animlod::point_mesh_max_squared_distances(mesh, points.data(), point_count, short_ends.data(), 2, 0,
                                                  floors.data(), scratch.data())
            .message.find("the last end is not the point count") != std::string::npos);
  CHECK(animlod::point_mesh_max_squared_distances(mesh, points.data(), point_count, falling.data(), 3, 0,
                                                  floors.data(), scratch.data())
            .message.find("segment_ends[1]") != std::string::npos);
}

TEST_CASE("point-to-mesh distances of no frame read nothing") {
  // (0, N, 3) points against (0, V, 3) vertices: the faces are checked, no position is read.
  const std::vector<int32_t> f{0, 1, 2};
  const animlod::TriangleMeshView none{nullptr, f.data(), 3, 1, 0};
  double out = -1.0;
  CHECK(animlod::point_mesh_squared_distance(none, nullptr, 5, 0, nullptr));
  CHECK(animlod::point_mesh_max_squared_distance(none, nullptr, 5, 0, 0.25, out));
  CHECK(out == 0.25);
  const std::vector<int32_t> bad{0, 1, 3};
  CHECK(animlod::point_mesh_squared_distance({nullptr, bad.data(), 3, 1, 0}, nullptr, 5, 0, nullptr).message.find(
            "faces[0]") != std::string::npos);
}
