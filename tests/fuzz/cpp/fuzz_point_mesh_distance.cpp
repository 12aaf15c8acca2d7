// Fuzz harness: point_mesh_squared_distance on a decoded animated mesh (layout in fuzz_input.hpp),
// then: u8 mode (bit 0: raw float32 points), u16 N = value % 1025, T * N * 3 point coordinates.
// Invariants: the call fails exactly when there is no face, an index outside [0, V) or a
// non-finite coordinate, with a message; on success every distance is finite, >= 0, no more
// than the distance to the nearest vertex of a face in the same frame, and the same on one
// thread as on two; point_mesh_max_squared_distance gives their largest to the bit, from a
// floor of 0 and of half of it, on one thread and on two.
#include <cmath>
#include <vector>

#include "animlod/point_mesh_distance.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  animlod::fuzz::FuzzInput in(data, size);
  const animlod::fuzz::FuzzMesh mesh = animlod::fuzz::decode_mesh(in);
  const bool raw = in.take<uint8_t>() & 1u;
  const size_t point_count = in.take<uint16_t>() % 1025;
  const size_t frames = mesh.frame_count, vertices = mesh.vertex_count;
  std::vector<double> points(frames * point_count * 3);
  for (double& value : points) value = in.coordinate(raw);
  const std::vector<double> positions(mesh.frames.begin(), mesh.frames.end());
  bool valid = mesh.face_count > 0;
  for (int32_t index : mesh.faces) valid = valid && index >= 0 && static_cast<size_t>(index) < vertices;
  for (double value : positions) valid = valid && std::isfinite(value);
  for (double value : points) valid = valid && std::isfinite(value);

  const animlod::TriangleMeshView view{positions.data(), mesh.faces.data(), vertices, mesh.face_count, frames};
  std::vector<double> one(frames * point_count), two(frames * point_count);
  const animlod::Status status = animlod::point_mesh_squared_distance(view, points.data(), point_count, 1, one.data());
  ANIMLOD_FUZZ_REQUIRE(status.ok == valid);
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
    return 0;
  }
  ANIMLOD_FUZZ_REQUIRE(animlod::point_mesh_squared_distance(view, points.data(), point_count, 2, two.data()).ok);
  ANIMLOD_FUZZ_REQUIRE(one == two);
  double largest = 0.0;
  for (double d : one) largest = std::fmax(largest, d);
  for (const unsigned threads : {1u, 2u})
    for (const double floor : {0.0, 0.5 * largest}) {
      double out = -1.0;
      ANIMLOD_FUZZ_REQUIRE(
          animlod::point_mesh_max_squared_distance(view, points.data(), point_count, threads, floor, out).ok);
      ANIMLOD_FUZZ_REQUIRE(out == largest);
    }
  for (size_t t = 0; t < frames; ++t)
    for (size_t i = 0; i < point_count; ++i) {
      const double* p = &points[3 * (t * point_count + i)];
      double nearest_vertex = INFINITY;
      for (int32_t index : mesh.faces) {
        const double* v = &positions[3 * (t * vertices + static_cast<size_t>(index))];
        const double dx = p[0] - v[0], dy = p[1] - v[1], dz = p[2] - v[2];
        nearest_vertex = std::fmin(nearest_vertex, dx * dx + dy * dy + dz * dz);
      }
      const double d = one[t * point_count + i];
      ANIMLOD_FUZZ_REQUIRE(std::isfinite(d) && d >= 0.0);
      ANIMLOD_FUZZ_REQUIRE(d <= nearest_vertex * (1.0 + 1e-9));
    }
  return 0;
}
