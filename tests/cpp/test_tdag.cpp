#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "../../cpp/src/crc32.hpp"
#include "animlod/mesh_validation.hpp"
#include "animlod/tdag.hpp"
#include "animlod/tdag_player.hpp"
#include "test_aqem_meshes.hpp"

using animlod::ApproximationLevel;
using animlod::Governing;
using animlod::TdagCut;
using animlod::TdagMesh;
using animlod::TdagOptions;
using animlod::TemporalDag;
using animlod::testing::OwnedAnimatedMesh;

namespace {

TemporalDag build(const OwnedAnimatedMesh& mesh, TdagOptions options = {}) {
  TemporalDag dag;
  const animlod::Status status = animlod::build_temporal_dag(mesh.view(), options, dag);
  REQUIRE_MESSAGE(status.ok, status.message);
  return dag;
}

// A bending tube that also swings and grows as a whole (an affine part and a bend).
OwnedAnimatedMesh swinging_tube(int frames) {
  OwnedAnimatedMesh mesh = animlod::testing::bending_tube(16, 12, frames, 1.4);
  for (size_t f = 0; f < mesh.frame_count; ++f) {
    const double a = 0.2 * double(f), s = 1.0 + 0.05 * double(f);
    for (size_t v = 0; v < mesh.vertex_count; ++v) {
      float* p = &mesh.frames[(f * mesh.vertex_count + v) * 3];
      const double x = p[0], y = p[1];
      p[0] = float(s * (std::cos(a) * x - std::sin(a) * y) + 0.3 * double(f));
      p[1] = float(s * (std::sin(a) * x + std::cos(a) * y));
    }
  }
  return mesh;
}

// Nodes and faces (as node triples, smallest node first, orientation kept), sorted.
struct CanonicalMesh {
  std::vector<int32_t> nodes;
  std::vector<std::array<int32_t, 3>> faces;
  bool operator==(const CanonicalMesh& o) const { return nodes == o.nodes && faces == o.faces; }
};

CanonicalMesh canonical(const TdagMesh& mesh) {
  CanonicalMesh out;
  out.nodes = mesh.nodes;
  std::sort(out.nodes.begin(), out.nodes.end());
  for (size_t f = 0; f < mesh.faces.size(); f += 3) {
    std::array<int32_t, 3> face{mesh.nodes[size_t(mesh.faces[f])], mesh.nodes[size_t(mesh.faces[f + 1])],
                                mesh.nodes[size_t(mesh.faces[f + 2])]};
    std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
    out.faces.push_back(face);
  }
  std::sort(out.faces.begin(), out.faces.end());
  return out;
}

CanonicalMesh current(const TdagCut& cut) {
  TdagMesh mesh;
  cut.mesh(mesh);
  return canonical(mesh);
}

CanonicalMesh fresh(const TemporalDag& dag, int32_t frame, double tolerance) {
  TdagCut cut(dag);
  const animlod::Status status = cut.query(frame, tolerance);
  REQUIRE_MESSAGE(status.ok, status.message);
  return current(cut);
}

// The mesh is a valid manifold (the checks every algorithm applies to its input) and every
// input vertex is within `tolerance` of the vertex standing for it (plus float rounding).
void check_cut(const TemporalDag& dag, const TdagCut& cut, double tolerance) {
  TdagMesh mesh;
  cut.mesh(mesh);
  const animlod::AnimatedMeshView view{mesh.positions.data(), mesh.faces.data(), 1, mesh.nodes.size(),
                                       mesh.faces.size() / 3};
  const animlod::Status valid = animlod::validate_animated_mesh(view);
  REQUIRE_MESSAGE(valid.ok, valid.message);
  CHECK(mesh.error_bound <= tolerance);
  std::vector<float> original(dag.vertex_count() * 3);
  dag.frame_positions(cut.frame(), original.data());
  std::vector<int32_t> map;
  cut.input_vertex_map(map);
  for (size_t v = 0; v < map.size(); ++v) {
    REQUIRE(map[v] >= 0);
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += std::pow(double(original[3 * v + k]) - mesh.positions[3 * size_t(map[v]) + k], 2);
    CHECK(std::sqrt(d2) <= tolerance + 1e-5);
  }
}

double largest_bound(const TemporalDag& dag, int32_t frame) {
  double largest = 0.0;
  for (size_t c = 0; c < dag.collapse_count(); ++c)
    if (dag.alive(c).alive_at(frame)) largest = std::max(largest, dag.error_bound(c, frame));
  return largest;
}

}  // namespace

TEST_CASE("tdag: governed build, bounds monotone up the hierarchy and along dependencies") {
  const OwnedAnimatedMesh mesh = swinging_tube(6);
  for (Governing governing : {Governing::first, Governing::average, Governing::frame, Governing::aqem}) {
    TdagOptions options;
    options.governing = governing;
    options.governing_frame = 4;
    const TemporalDag dag = build(mesh, options);
    CAPTURE(static_cast<int>(governing));
    CHECK(dag.collapse_count() > mesh.vertex_count / 2);
    const auto frames = static_cast<int32_t>(mesh.frame_count);
    for (size_t c = 0; c < dag.collapse_count(); ++c) {
      CHECK(dag.alive(c) == animlod::TimeTag(0, frames));  // one order for every frame
      for (int32_t t = 0; t < frames; ++t) {
        const double bound = dag.error_bound(c, t);
        for (int32_t d : dag.dependencies_at(c, t)) CHECK(dag.error_bound(size_t(d) - mesh.vertex_count, t) <= bound);
        for (int32_t child : {dag.kept_child(c), dag.removed_child(c)})
          if (child >= int32_t(mesh.vertex_count))
            CHECK(dag.error_bound(size_t(child) - mesh.vertex_count, t) <= bound);
      }
    }
  }
}

TEST_CASE("tdag: random queries give valid manifold meshes within the tolerance") {
  const OwnedAnimatedMesh mesh = swinging_tube(5);
  const TemporalDag dag = build(mesh);
  std::mt19937 random(7);
  TdagCut cut(dag);
  for (int i = 0; i < 40; ++i) {
    const auto frame = int32_t(random() % mesh.frame_count);
    const double tolerance = largest_bound(dag, frame) * std::pow(std::uniform_real_distribution<double>(0, 1)(random), 2);
    REQUIRE(cut.query(frame, tolerance).ok);
    check_cut(dag, cut, tolerance);
  }
  // Tolerance 0 is the input itself; a huge tolerance is the coarsest mesh.
  REQUIRE(cut.query(2, 0.0).ok);
  CHECK(cut.active_vertex_count() == mesh.vertex_count);
  CHECK(cut.active_face_count() == mesh.faces.size() / 3);
  REQUIRE(cut.query(2, 1e9).ok);
  CHECK(cut.active_face_count() < 40);
  check_cut(dag, cut, 1e9);
}

TEST_CASE("tdag: cuts after any sequence of advance and refine equal fresh queries") {
  const OwnedAnimatedMesh mesh = swinging_tube(8);
  for (Governing governing : {Governing::first, Governing::online}) {
    TdagOptions options;
    options.governing = governing;
    options.history_weight = 0.5;
    const TemporalDag dag = build(mesh, options);
    std::mt19937 random(11);
    const double scale = largest_bound(dag, 0);
    TdagCut cut(dag);
    double tolerance = 0.05 * scale;
    REQUIRE(cut.query(0, tolerance).ok);
    for (int step = 0; step < 60; ++step) {
      if (random() % 3 == 0) {
        tolerance = scale * std::pow(std::uniform_real_distribution<double>(0, 1)(random), 3);
        REQUIRE(cut.refine(tolerance).ok);
      } else {
        const auto frame = random() % 4 == 0 ? int32_t(random() % mesh.frame_count)
                                             : std::min<int32_t>(cut.frame() + 1, int32_t(mesh.frame_count) - 1);
        REQUIRE(cut.advance(frame).ok);
      }
      CAPTURE(step);
      REQUIRE(current(cut) == fresh(dag, cut.frame(), tolerance));
      check_cut(dag, cut, tolerance);
    }
  }
}

TEST_CASE("tdag: online construction with a huge history weight equals the governed build") {
  const OwnedAnimatedMesh mesh = swinging_tube(5);
  TdagOptions governed;
  governed.check_inversion = false;  // the online build tests flips in every frame, governed in frame 0
  TdagOptions online = governed;
  online.governing = Governing::online;
  online.history_weight = 1e9;
  const TemporalDag a = build(mesh, governed), b = build(mesh, online);
  REQUIRE(a.collapse_count() == b.collapse_count());
  for (size_t c = 0; c < a.collapse_count(); ++c) {
    CHECK(a.kept_child(c) == b.kept_child(c));
    CHECK(a.removed_child(c) == b.removed_child(c));
    CHECK(a.alive(c) == b.alive(c));
    for (int32_t t = 0; t < int32_t(mesh.frame_count); ++t) {
      CHECK(a.dependencies_at(c, t) == b.dependencies_at(c, t));
      CHECK(a.error_bound(c, t) == b.error_bound(c, t));
    }
  }
  // lambda = 0: every frame its own order, so some collapses live on some frames only.
  online.history_weight = 0.0;
  const TemporalDag own = build(mesh, online);
  size_t partial = 0;
  for (size_t c = 0; c < own.collapse_count(); ++c) partial += own.alive(c) != animlod::TimeTag(0, 5);
  CHECK(partial > 0);
  CHECK(own.collapse_count() > a.collapse_count());
}

TEST_CASE("tdag: view-dependent tolerance refines near the camera") {
  const OwnedAnimatedMesh mesh = swinging_tube(3);
  const TemporalDag dag = build(mesh);
  TdagCut cut(dag);
  animlod::ViewTolerance view;
  view.camera[0] = -1.5;  // beyond the left end of the tube (x = -1 in frame 0)
  view.pixels = 30.0;
  view.focal_pixels = 300.0;
  REQUIRE(cut.query_view(0, view).ok);
  TdagMesh out;
  cut.mesh(out);
  const animlod::AnimatedMeshView single{out.positions.data(), out.faces.data(), 1, out.nodes.size(), out.faces.size() / 3};
  REQUIRE(animlod::validate_animated_mesh(single).ok);
  size_t near = 0, far = 0;
  for (size_t i = 0; i < out.nodes.size(); ++i) (out.positions[3 * i] < 0.0f ? near : far) += 1;
  CHECK(near > far);
  // Moving the camera to the other end and updating equals a fresh view query there.
  view.camera[0] = 3.0;
  REQUIRE(cut.refine_view(view).ok);
  TdagCut again(dag);
  REQUIRE(again.query_view(0, view).ok);
  CHECK(current(cut) == current(again));
  REQUIRE(cut.advance(2).ok);
  REQUIRE(again.query_view(2, view).ok);
  CHECK(current(cut) == current(again));
}

TEST_CASE("tdag: the three approximation levels of Section 5") {
  const OwnedAnimatedMesh mesh = swinging_tube(4);
  const TemporalDag dag = build(mesh);
  const double tolerance = 0.02 * largest_bound(dag, 0);
  TdagCut cut(dag);
  REQUIRE(cut.query(1, tolerance).ok);
  TdagMesh level1, level2, level3;
  REQUIRE(cut.approximate(2, ApproximationLevel::affine, level1).ok);
  REQUIRE(cut.approximate(2, ApproximationLevel::residual, level2).ok);
  // Levels 1 and 2: the previous cut; level 1 moves frame 1's residuals by A_2.
  CHECK(level1.cut_frame == 1);
  CHECK(level1.residual_frame == 1);
  CHECK(level2.residual_frame == 2);
  CHECK(level1.faces == level2.faces);
  for (size_t i = 0; i < level1.nodes.size(); ++i) {
    float expected[3];
    animlod::apply_affine(dag.affine_map(2), dag.residuals(1) + 3 * size_t(dag.representative(level1.nodes[i])), 1, expected);
    for (int k = 0; k < 3; ++k) CHECK(level1.positions[3 * i + k] == doctest::Approx(expected[k]));
  }
  REQUIRE(cut.approximate(2, ApproximationLevel::full, level3).ok);
  CHECK(level3.cut_frame == 2);
  CHECK(canonical(level3) == fresh(dag, 2, tolerance));
  check_cut(dag, cut, tolerance);
}

TEST_CASE("tdag: save and load round trip, damaged files are named errors") {
  const OwnedAnimatedMesh mesh = swinging_tube(4);
  TdagOptions options;
  options.governing = Governing::online;
  options.history_weight = 0.2;
  const TemporalDag dag = build(mesh, options);
  std::vector<uint8_t> bytes, again;
  REQUIRE(animlod::serialize_temporal_dag(dag, bytes).ok);
  TemporalDag loaded;
  const animlod::Status status = animlod::deserialize_temporal_dag(bytes.data(), bytes.size(), loaded);
  REQUIRE_MESSAGE(status.ok, status.message);
  REQUIRE(animlod::serialize_temporal_dag(loaded, again).ok);
  CHECK(again == bytes);
  CHECK(loaded.governing() == Governing::online);
  size_t runs = 0;
  for (size_t c = 0; c < dag.collapse_count(); ++c) {
    CHECK(loaded.alive(c) == dag.alive(c));
    CHECK(loaded.error_run_count(c) == dag.error_run_count(c));
    runs += dag.error_run_count(c);
    for (int32_t t = 0; t < 4; ++t) CHECK(loaded.error_bound(c, t) == dag.error_bound(c, t));
  }
  CHECK(dag.error_run_count() == runs);
  CHECK(loaded.error_run_count() == runs);
  for (int32_t t = 0; t < 4; ++t) {
    std::vector<float> a(mesh.vertex_count * 3), b(mesh.vertex_count * 3);
    dag.frame_positions(t, a.data());
    loaded.frame_positions(t, b.data());
    CHECK(a == b);
    CHECK(fresh(dag, t, 0.03) == fresh(loaded, t, 0.03));
  }

  auto load_error = [](std::vector<uint8_t> data) {
    TemporalDag out;
    const animlod::Status s = animlod::deserialize_temporal_dag(data.data(), data.size(), out);
    CHECK_FALSE(s.ok);
    CHECK(out.empty());
    return s.message;
  };
  std::vector<uint8_t> damaged = bytes;
  damaged[bytes.size() / 2] ^= 0x40;
  CHECK(load_error(damaged) == "corrupted TDAG file: checksum mismatch");
  damaged = bytes;
  damaged[8] = 0;  // format version 0
  CHECK(load_error(damaged).find("TDAG format version 0 was written by an older animlod") == 0);
  damaged[8] = 9;
  CHECK(load_error(damaged).find("written by a newer animlod") != std::string::npos);
  CHECK(load_error({bytes.begin(), bytes.end() - 10}).find("truncated") != std::string::npos);
  CHECK(load_error({'h', 'e', 'l', 'l', 'o'}) == "not a TDAG file (no ANLDTDAG signature)");
}

TEST_CASE("tdag: a file loads a chunk at a time as from bytes, its errors named with the path") {
  const OwnedAnimatedMesh mesh = swinging_tube(6);
  TdagOptions options;
  options.governing = Governing::online;
  const TemporalDag dag = build(mesh, options);
  std::vector<uint8_t> bytes;
  REQUIRE(animlod::serialize_temporal_dag(dag, bytes).ok);
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "animlod_test_tdag_chunks";
  std::filesystem::create_directories(folder);
  auto write = [&](const std::string& name, const std::vector<uint8_t>& data) {
    const std::string path = (folder / name).string();
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
    return path;
  };
  // The body between the header and the checksum replaced, with its length and checksum made right.
  auto rewrapped = [&](std::vector<uint8_t> body) {
    std::vector<uint8_t> file(bytes.begin(), bytes.begin() + 20);
    const uint64_t length = body.size();
    std::memcpy(&file[12], &length, 8);
    const uint32_t crc = animlod::detail::crc32(body.data(), body.size());
    file.insert(file.end(), body.begin(), body.end());
    file.insert(file.end(), reinterpret_cast<const uint8_t*>(&crc), reinterpret_cast<const uint8_t*>(&crc) + 4);
    return file;
  };
  const std::vector<uint8_t> body(bytes.begin() + 20, bytes.end() - 4);
  std::vector<uint8_t> longer = body, damaged = bytes;
  longer.push_back(0);
  damaged[bytes.size() / 2] ^= 0x40;
  const std::vector<std::string> refused = {write("short.tdag", rewrapped({body.begin(), body.end() - 9})),
                                            write("long.tdag", rewrapped(longer)), write("damaged.tdag", damaged),
                                            write("cut.tdag", {bytes.begin(), bytes.end() - 10})};
  const std::string path = write("good.tdag", bytes);
  for (const size_t chunk : {size_t{1}, size_t{2}, size_t{3}, size_t{7}, size_t{64}, size_t{4096}, size_t{1} << 20}) {
    CAPTURE(chunk);
    TemporalDag loaded;
    const animlod::Status status = animlod::load_temporal_dag(path, loaded, chunk);
    REQUIRE_MESSAGE(status.ok, status.message);
    std::vector<uint8_t> again;
    REQUIRE(animlod::serialize_temporal_dag(loaded, again).ok);
    CHECK(again == bytes);
    for (const std::string& bad : refused) {
      std::ifstream stream(bad, std::ios::binary);
      const std::vector<uint8_t> data((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
      TemporalDag from_bytes, from_file;
      const animlod::Status expected = animlod::deserialize_temporal_dag(data.data(), data.size(), from_bytes);
      const animlod::Status found = animlod::load_temporal_dag(bad, from_file, chunk);
      CHECK_FALSE(expected.ok);
      CHECK(found.message == bad + ": " + expected.message);
      CHECK(from_file.empty());
    }
  }
  TemporalDag none;
  CHECK(animlod::load_temporal_dag((folder / "missing.tdag").string(), none).message ==
        (folder / "missing.tdag").string() + ": cannot open");
  CHECK(animlod::load_temporal_dag(folder.string(), none).message == folder.string() + ": a directory, not a TDAG file");
  std::filesystem::remove_all(folder);
}

TEST_CASE("tdag: a file written a chunk at a time has the bytes of one written whole") {
  const TemporalDag dag = build(swinging_tube(6));
  std::vector<uint8_t> whole;
  REQUIRE(animlod::serialize_temporal_dag(dag, whole).ok);
  struct MemorySink : animlod::TdagFileSink {
    std::vector<uint8_t> bytes;
    size_t fail_after = SIZE_MAX;  // bytes appended before append fails
    size_t appends = 0;
    bool append(const uint8_t* data, size_t size) override {
      if (bytes.size() + size > fail_after) return false;
      bytes.insert(bytes.end(), data, data + size);
      appends += 1;
      return true;
    }
    bool overwrite(size_t offset, const uint8_t* data, size_t size) override {
      if (offset + size > bytes.size()) return false;
      std::copy_n(data, size, bytes.begin() + static_cast<std::ptrdiff_t>(offset));
      return true;
    }
  };
  for (const size_t chunk : {size_t{1}, size_t{3}, size_t{64}, size_t{4096}, size_t{1} << 20}) {
    CAPTURE(chunk);
    MemorySink sink;
    const animlod::Status status = animlod::write_temporal_dag(dag, sink, chunk);
    REQUIRE_MESSAGE(status.ok, status.message);
    CHECK(sink.bytes == whole);
    CHECK(sink.appends >= std::min<size_t>(whole.size() / (chunk + 64), 100));  // handed out in pieces
  }
  MemorySink full_disk;
  full_disk.fail_after = whole.size() / 2;
  CHECK(animlod::write_temporal_dag(dag, full_disk, 64).message == "write failed");

  const std::filesystem::path path = std::filesystem::temp_directory_path() / "animlod_test_tdag_written.tdag";
  REQUIRE(animlod::save_temporal_dag(dag, path.string()).ok);
  std::ifstream stream(path, std::ios::binary);
  CHECK(std::vector<uint8_t>((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>()) == whole);
  std::filesystem::remove(path);
}

TEST_CASE("tdag: every file the builder writes loads, a collapse ordered before its child does not") {
  // The reader checks that each collapse child is in the dependency closure of its parent on
  // every frame (tdag_io.cpp); the builder links children only through chains of dependencies,
  // so this walks several meshes and every governing mode, online with several history weights.
  const std::vector<OwnedAnimatedMesh> meshes = {swinging_tube(6),
                                                 animlod::testing::sphere(9, 12, 4),
                                                 animlod::testing::jittering_sphere(8, 10, 5, 0.03f),
                                                 animlod::testing::bending_tube(14, 9, 5, 1.5),
                                                 animlod::testing::subdivided_cube(4),
                                                 animlod::testing::grid(7)};
  size_t files = 0;
  for (size_t m = 0; m < meshes.size(); ++m) {
    const OwnedAnimatedMesh& mesh = meshes[m];
    for (int mode = 0; mode < 8; ++mode) {
      TdagOptions options;
      const Governing modes[] = {Governing::first, Governing::average, Governing::frame, Governing::aqem};
      options.governing = mode < 4 ? modes[mode] : Governing::online;
      options.governing_frame = int32_t(mesh.frame_count) - 1;
      options.history_weight = mode == 4 ? 0.0 : mode == 5 ? 0.3 : mode == 6 ? 2.0 : 1e9;
      options.weld = mode != 2;
      CAPTURE(m);
      CAPTURE(mode);
      const TemporalDag dag = build(mesh, options);
      std::vector<uint8_t> bytes;
      REQUIRE(animlod::serialize_temporal_dag(dag, bytes).ok);
      TemporalDag loaded;
      const animlod::Status status = animlod::deserialize_temporal_dag(bytes.data(), bytes.size(), loaded);
      CHECK_MESSAGE(status.ok, status.message);
      files += status.ok;
    }
  }
  CHECK(files == 48);

  // The fuzz finding (tests/fuzz/crashes/tdag/): a crane body whose collapse names another kept
  // child, wrapped in a valid header and checksum, is refused, naming the collapse and child.
  const std::filesystem::path crash =
      std::filesystem::path(__FILE__).parent_path() / "../fuzz/crashes/tdag/crash-2cf496c94f55c031";
  std::ifstream stream(crash, std::ios::binary);
  REQUIRE_MESSAGE(stream.good(), crash.string());
  const std::vector<uint8_t> input((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  REQUIRE(input.size() > 3);
  REQUIRE(input[0] == 0);  // flag bit 0 clear: the rest is a body (fuzz_tdag.cpp)
  const std::vector<uint8_t> body(input.begin() + 3, input.end());
  uint32_t crc = 0xFFFFFFFFu;
  for (uint8_t byte : body) {
    crc ^= byte;
    for (int k = 0; k < 8; ++k) crc = (crc & 1u) ? 0xEDB88320u ^ (crc >> 1) : crc >> 1;
  }
  crc ^= 0xFFFFFFFFu;
  std::vector<uint8_t> file = {'A', 'N', 'L', 'D', 'T', 'D', 'A', 'G'};
  const uint32_t version = 1;  // the body was found with the format of version 1
  const uint64_t length = body.size();
  file.insert(file.end(), reinterpret_cast<const uint8_t*>(&version), reinterpret_cast<const uint8_t*>(&version) + 4);
  file.insert(file.end(), reinterpret_cast<const uint8_t*>(&length), reinterpret_cast<const uint8_t*>(&length) + 8);
  file.insert(file.end(), body.begin(), body.end());
  file.insert(file.end(), reinterpret_cast<const uint8_t*>(&crc), reinterpret_cast<const uint8_t*>(&crc) + 4);
  TemporalDag damaged;
  const animlod::Status refused = animlod::deserialize_temporal_dag(file.data(), file.size(), damaged);
  CHECK_FALSE(refused.ok);
  CHECK(damaged.empty());
  INFO(refused.message);
  CHECK(refused.message.find("corrupted TDAG file: collapse ") == 0);
  CHECK(refused.message.find("child, node ") != std::string::npos);
  CHECK(refused.message.find("is not among the collapses it depends on") != std::string::npos);
}

// Double-sided cloth as exporters write it: every face again in the reverse turn, on vertices
// of its own. Kept as faces, both sides were cut apart at every edge and locked: no collapse.
TEST_CASE("tdag: a two-sided sheet simplifies as its front and cuts hand out both sides") {
  OwnedAnimatedMesh front = animlod::testing::grid(8);  // 81 vertices, 128 faces
  for (int f = 1; f < 3; ++f)
    for (size_t v = 0; v < 81; ++v) {
      const float x = front.frames[3 * v], y = front.frames[3 * v + 1];
      front.frames.insert(front.frames.end(), {x, y, 0.1f * float(f) * std::sin(3.0f * x) * std::cos(2.0f * y)});
    }
  front.frame_count = 3;
  OwnedAnimatedMesh sheet = front;
  sheet.vertex_count = 162;
  sheet.frames.clear();
  for (size_t f = 0; f < 3; ++f)
    for (int side = 0; side < 2; ++side)
      sheet.frames.insert(sheet.frames.end(), front.frames.begin() + f * 243, front.frames.begin() + (f + 1) * 243);
  for (size_t f = 0; f < 128; ++f)
    for (size_t c : {0, 2, 1}) sheet.faces.push_back(front.faces[3 * f + c] + 81);
  const TemporalDag one = build(front), two = build(sheet);
  REQUIRE(one.collapse_count() > 0);
  CHECK(two.collapse_count() == one.collapse_count());
  REQUIRE(two.face_count() == 128);
  for (size_t f = 0; f < 128; ++f) {
    CHECK_FALSE(one.two_sided(f));
    CHECK(two.two_sided(f));
  }
  for (size_t v = 0; v < 81; ++v) CHECK(two.input_points()[v + 81] == two.input_points()[v]);
  for (double tolerance : {0.0, 0.02, 1e9}) {
    TdagCut a(one), b(two);
    REQUIRE(a.query(2, tolerance).ok);
    REQUIRE(b.query(2, tolerance).ok);
    TdagMesh front_mesh, both;
    a.mesh(front_mesh);
    b.mesh(both);
    const size_t m = front_mesh.faces.size();
    REQUIRE(both.faces.size() == 2 * m);
    CHECK(both.positions == front_mesh.positions);
    CHECK(std::equal(front_mesh.faces.begin(), front_mesh.faces.end(), both.faces.begin()));
    for (size_t f = 0; f < m; f += 3)
      for (size_t c = 0; c < 3; ++c) CHECK(both.faces[m + f + c] == front_mesh.faces[f + (3 - c) % 3]);  // 0, 2, 1
  }
  std::vector<uint8_t> bytes, again;
  REQUIRE(animlod::serialize_temporal_dag(two, bytes).ok);
  TemporalDag loaded;
  REQUIRE(animlod::deserialize_temporal_dag(bytes.data(), bytes.size(), loaded).ok);
  for (size_t f = 0; f < 128; ++f) CHECK(loaded.two_sided(f));
  REQUIRE(animlod::serialize_temporal_dag(loaded, again).ok);
  CHECK(again == bytes);
}

TEST_CASE("tdag: bad input is a named error") {
  OwnedAnimatedMesh mesh = swinging_tube(3);
  TdagOptions options;
  TemporalDag dag;
  options.governing = Governing::frame;
  options.governing_frame = 3;
  CHECK(animlod::build_temporal_dag(mesh.view(), options, dag).message == "governing_frame: frame 3 outside [0, 3)");
  options = {};
  options.history_weight = -1.0;
  CHECK(animlod::build_temporal_dag(mesh.view(), options, dag).message.find("history_weight") == 0);
  mesh.frames[(mesh.vertex_count + 5) * 3] = NAN;
  CHECK(animlod::build_temporal_dag(mesh.view(), {}, dag).message == "frame 1, vertex 5: non-finite position");
  CHECK(dag.empty());

  const TemporalDag good = build(swinging_tube(3));
  TdagCut cut(good);
  CHECK(cut.advance(1).message.find("no query yet") != std::string::npos);
  CHECK(cut.query(3, 0.1).message == "frame: 3 outside [0, 3)");
  CHECK(cut.query(0, -0.5).message.find("tolerance: must be >= 0") == 0);
  CHECK_FALSE(cut.query(0, NAN).ok);
}

TEST_CASE("tdag player: double-buffered walk hands out the same meshes as one cut") {
  const OwnedAnimatedMesh mesh = swinging_tube(10);
  const TemporalDag dag = build(mesh);
  const double tolerance = 0.03 * largest_bound(dag, 0);
  animlod::TdagPlayer player(dag);
  REQUIRE(player.start(tolerance, 0).ok);
  TdagCut reference(dag);
  REQUIRE(reference.query(0, tolerance).ok);
  TdagMesh out, expected;
  const ApproximationLevel plan[] = {ApproximationLevel::full, ApproximationLevel::full, ApproximationLevel::residual,
                                     ApproximationLevel::full, ApproximationLevel::affine};
  for (int32_t t = 0; t < 10; ++t) {
    const ApproximationLevel level = plan[t % 5];
    REQUIRE(player.next(level, out).ok);
    if (level == ApproximationLevel::full) {
      REQUIRE(reference.approximate(t, level, expected).ok);
      CHECK(canonical(out) == canonical(expected));
      CHECK(out.cut_frame == t);
    } else {
      CHECK(out.cut_frame < t);
    }
  }
  CHECK(player.done());
  CHECK_FALSE(player.next(ApproximationLevel::full, out).ok);

  animlod::PlayerOptions options;
  options.tolerance = tolerance;
  animlod::PlayerReport report;
  REQUIRE(animlod::play_temporal_dag(dag, options, report).ok);
  CHECK(report.frames == 9);
  CHECK(report.levels[2].max_error <= tolerance + 1e-5);  // level 3 keeps the bound
  CHECK(report.full_query.max_error <= tolerance + 1e-5);
  CHECK(report.levels[0].max_error > report.levels[2].max_error);  // the tube bends: level 1 lags
  CHECK(report.levels[2].mean_faces == doctest::Approx(report.full_query.mean_faces));
}
