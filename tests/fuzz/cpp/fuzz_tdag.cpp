// Fuzz harness: the .tdag reader (deserialize_temporal_dag) and the cuts of whatever it accepts.
// Input:
//   u8  flags       bit 0: the rest is a whole file as given (magic, version, length, CRC);
//                   else the rest is the body, wrapped here in a valid header and CRC so that
//                   mutations reach the parser behind the checksum (seeds: real bodies)
//   u8  tolerance   value / 64 asset units; 255 -> NaN, 254 -> -1 (both refused by query),
//                   253 -> +inf
//   u8  frame       the first frame queried: value % F (255 -> F, refused)
//   the rest        body or file (serialize_temporal_dag's layout, tdag_io.cpp)
// Invariants: an error has a message; an accepted TDAG serializes to bytes that load again and
// serialize to the same bytes, also when written a few bytes at a time; its faces and input points are in range; every query, advance,
// refine and approximation at each level hands out a mesh whose faces index its positions and
// whose nodes exist, with a map of the TDAG's vertices (leaves) into those positions.
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "animlod/tdag.hpp"
#include "fuzz_input.hpp"

namespace {

uint32_t crc32(const uint8_t* bytes, size_t size) {
  uint32_t c = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) {
    c ^= bytes[i];
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

std::vector<uint8_t> wrap(const uint8_t* body, size_t size) {
  std::vector<uint8_t> file = {'A', 'N', 'L', 'D', 'T', 'D', 'A', 'G'};
  const uint32_t version = animlod::kTdagFormatVersion;
  const uint64_t length = size;
  const uint32_t crc = crc32(body, size);
  file.insert(file.end(), reinterpret_cast<const uint8_t*>(&version), reinterpret_cast<const uint8_t*>(&version) + 4);
  file.insert(file.end(), reinterpret_cast<const uint8_t*>(&length), reinterpret_cast<const uint8_t*>(&length) + 8);
  file.insert(file.end(), body, body + size);
  file.insert(file.end(), reinterpret_cast<const uint8_t*>(&crc), reinterpret_cast<const uint8_t*>(&crc) + 4);
  return file;
}

void check_mesh(const animlod::TemporalDag& dag, const animlod::TdagMesh& mesh) {
  ANIMLOD_FUZZ_REQUIRE(mesh.positions.size() % 3 == 0 && mesh.faces.size() % 3 == 0);
  const size_t vertex_count = mesh.positions.size() / 3;
  ANIMLOD_FUZZ_REQUIRE(mesh.nodes.size() == vertex_count);
  for (int32_t node : mesh.nodes) ANIMLOD_FUZZ_REQUIRE(node >= 0 && static_cast<size_t>(node) < dag.node_count());
  for (int32_t index : mesh.faces) ANIMLOD_FUZZ_REQUIRE(index >= 0 && static_cast<size_t>(index) < vertex_count);
  ANIMLOD_FUZZ_REQUIRE(mesh.frame >= 0 && static_cast<size_t>(mesh.frame) < dag.frame_count());
}

void check_cut(const animlod::TemporalDag& dag, const animlod::TdagCut& cut) {
  animlod::TdagMesh mesh;
  cut.mesh(mesh);
  check_mesh(dag, mesh);
  ANIMLOD_FUZZ_REQUIRE(mesh.positions.size() / 3 == cut.active_vertex_count());
  ANIMLOD_FUZZ_REQUIRE(mesh.faces.size() / 3 == cut.active_face_count());
  std::vector<int32_t> map;
  cut.input_vertex_map(map);
  ANIMLOD_FUZZ_REQUIRE(map.size() == dag.vertex_count());  // per TDAG vertex (leaf), not per input_points entry
  for (int32_t index : map) ANIMLOD_FUZZ_REQUIRE(index >= -1 && static_cast<size_t>(index + 1) <= cut.active_vertex_count());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  animlod::fuzz::FuzzInput in(data, size);
  const uint8_t flags = in.take<uint8_t>();
  const uint8_t tolerance_byte = in.take<uint8_t>();
  const uint8_t frame_byte = in.take<uint8_t>();
  const uint8_t* rest = data + (size - in.remaining());
  const std::vector<uint8_t> file = in.flag(flags, 0) ? std::vector<uint8_t>(rest, rest + in.remaining())
                                                      : wrap(rest, in.remaining());
  animlod::TemporalDag dag;
  const animlod::Status status = animlod::deserialize_temporal_dag(file.data(), file.size(), dag);
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty() && dag.empty());
    return 0;
  }
  ANIMLOD_FUZZ_REQUIRE(!dag.empty() && dag.frame_count() > 0 && dag.vertex_count() > 0);
  for (size_t i = 0; i < 3 * dag.face_count(); ++i)
    ANIMLOD_FUZZ_REQUIRE(dag.faces()[i] >= 0 && static_cast<size_t>(dag.faces()[i]) < dag.vertex_count());
  for (size_t v = 0; v < dag.input_vertex_count(); ++v)
    ANIMLOD_FUZZ_REQUIRE(dag.input_points()[v] >= -1 && dag.input_points()[v] < static_cast<int32_t>(dag.vertex_count()));

  // Round trip: what was accepted saves, and the saved bytes are a fixed point.
  std::vector<uint8_t> saved, again;
  ANIMLOD_FUZZ_REQUIRE(animlod::serialize_temporal_dag(dag, saved).ok);
  animlod::TemporalDag reloaded;
  ANIMLOD_FUZZ_REQUIRE(animlod::deserialize_temporal_dag(saved.data(), saved.size(), reloaded).ok);
  ANIMLOD_FUZZ_REQUIRE(animlod::serialize_temporal_dag(reloaded, again).ok);
  ANIMLOD_FUZZ_REQUIRE(saved == again);
  struct MemorySink : animlod::TdagFileSink {  // the same bytes handed out a few at a time
    std::vector<uint8_t> bytes;
    bool append(const uint8_t* data, size_t size) override {
      bytes.insert(bytes.end(), data, data + size);
      return true;
    }
    bool overwrite(size_t offset, const uint8_t* data, size_t size) override {
      if (offset + size > bytes.size()) return false;
      std::memcpy(bytes.data() + offset, data, size);
      return true;
    }
  } pieces;
  ANIMLOD_FUZZ_REQUIRE(animlod::write_temporal_dag(reloaded, pieces, 5).ok);
  ANIMLOD_FUZZ_REQUIRE(pieces.bytes == saved);

  // Cuts: a query, every approximation level over a few frames, a refinement, a view query.
  const auto frames = static_cast<int32_t>(dag.frame_count());
  const double tolerance = tolerance_byte == 255   ? std::numeric_limits<double>::quiet_NaN()
                           : tolerance_byte == 254 ? -1.0
                           : tolerance_byte == 253 ? std::numeric_limits<double>::infinity()
                                                   : tolerance_byte / 64.0;
  const int32_t first = frame_byte == 255 ? frames : frame_byte % frames;
  animlod::TdagCut cut(dag);
  const animlod::Status queried = cut.query(first, tolerance);
  if (!queried) {
    ANIMLOD_FUZZ_REQUIRE(!queried.message.empty());
    ANIMLOD_FUZZ_REQUIRE(first == frames || !(tolerance >= 0.0));
    return 0;
  }
  check_cut(dag, cut);
  ANIMLOD_FUZZ_REQUIRE(cut.error_bound() <= tolerance);
  const std::array<animlod::ApproximationLevel, 3> levels = {
      animlod::ApproximationLevel::affine, animlod::ApproximationLevel::residual, animlod::ApproximationLevel::full};
  for (int32_t step = 1; step <= 4; ++step) {
    animlod::TdagMesh mesh;
    const animlod::Status approximated = cut.approximate((first + step) % frames, levels[step % 3], mesh);
    ANIMLOD_FUZZ_REQUIRE(approximated.ok);
    check_mesh(dag, mesh);
  }
  ANIMLOD_FUZZ_REQUIRE(cut.advance((first + 1) % frames).ok);
  check_cut(dag, cut);
  ANIMLOD_FUZZ_REQUIRE(cut.refine(tolerance * 4.0 + 0.01).ok);
  check_cut(dag, cut);
  ANIMLOD_FUZZ_REQUIRE(cut.refine(0.0).ok);
  check_cut(dag, cut);
  animlod::ViewTolerance view;
  view.camera[2] = 10.0 + tolerance_byte;
  ANIMLOD_FUZZ_REQUIRE(cut.query_view(frames - 1, view).ok);
  check_cut(dag, cut);
  return 0;
}
