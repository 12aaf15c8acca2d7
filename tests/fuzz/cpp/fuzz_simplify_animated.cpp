// Fuzz harness: simplify_animated (AQEM) with every option and per-vertex input decoded from the
// bytes. Input (little-endian), a fixed 12-byte header, the mesh, then per-vertex data:
//   u8 flags      bit 0 use_motion_features, 1 boundary_quadrics, 2 check_inversion,
//                 3 fold_limit 0, 4 boundary_is_feature, 5 placement on_edge,
//                 6 locked vertices given, 7 importance given
//   u8 flags2     bit 0 attributes given, 1 skin given, 2 levels as face counts, 3 frame subset
//                 given, 4 max_error finite, 5 the progress callback throws, 6 position
//                 attributes given, 7 face groups given
//   u8 levels     1 + value % 4
//   4 x u8        level sizes: ratio value / 255 (0 is an error), or face count value * M / 255
//   u8 max_frames, u8 max_error (value / 16), u8 feature_threshold (value / 64 rad),
//   u8 counts     bits 0-1 attribute count A, bit 2 weld off, bits 3-4 position attribute count B,
//                 bit 5 tip quadrics off
//   u8 influences (1 + value % 8)
//   the mesh layout of fuzz_input.hpp
//   then, each for V vertices when its flag is set: locked (u8, odd = locked), importance
//   (u8 / 16; 0 is invalid), attributes (A int16 / 64), skin joints (K x u8, 255 -> -1) and
//   weights (K x u8 / 255, 254 -> NaN), a frame subset (u8 count % 8, then u8 frames), position
//   attributes (B int16 / 64) and face groups (M x u8).
// Invariants on success: one level per target, finest first; level faces index the kept
// vertices and come from input faces; kept vertices ascend; the vertex map points at kept
// vertices (-1 only for vertices no kept face uses, or whose every piece lost all its faces, as
// aqem.hpp says; pieces are those of the engine's mesh preparation); positions (F, V', 3) are finite; a reached
// level has at most its target of faces; a locked vertex that a face uses stays where it was in
// every frame; per-vertex outputs have one row per kept vertex.
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "animlod/aqem.hpp"
#include "fuzz_input.hpp"
#include "mesh_preparation.hpp"

namespace {

// The manifold pieces the collapse engine works on (mesh_preparation.hpp, the same weld input as
// simplify_animated): piece of each input face (-1 for faces the preparation dropped), and the
// pieces holding a corner of each input vertex.
struct Pieces {
  std::vector<int32_t> of_face;                    // (M,)
  std::vector<std::vector<int32_t>> of_vertex;     // (V,)
  size_t count = 0;
};

Pieces engine_pieces(const animlod::fuzz::FuzzMesh& mesh, const animlod::AqemVertexData& data, bool weld) {
  animlod::detail::WeldInput input;
  input.position_attributes = data.position_attributes;
  input.position_attribute_count = data.position_attribute_count;
  input.attributes = data.attributes;
  input.attribute_count = data.attribute_count;
  input.skin_joints = data.skin_joints;
  input.skin_weights = data.skin_weights;
  input.influence_count = data.influence_count;
  input.face_groups = data.face_groups;
  input.weld = weld;
  input.mirror_two_sided = true;  // as simplify_animated prepares
  const animlod::detail::PreparedMesh prepared = animlod::detail::prepare_mesh(mesh.view(), input);
  // Faces joined across an edge of two points (the prepared faces are manifold): union-find.
  const size_t face_count = prepared.face_sources.size();
  std::vector<size_t> root(face_count);
  for (size_t f = 0; f < face_count; ++f) root[f] = f;
  auto find = [&](size_t x) {
    while (root[x] != x) x = root[x] = root[root[x]];
    return x;
  };
  std::map<std::pair<int32_t, int32_t>, size_t> edge_face;
  for (size_t f = 0; f < face_count; ++f)
    for (size_t k = 0; k < 3; ++k) {
      const int32_t a = prepared.faces[3 * f + k], b = prepared.faces[3 * f + (k + 1) % 3];
      const auto [it, added] = edge_face.emplace(std::make_pair(std::min(a, b), std::max(a, b)), f);
      if (!added) root[find(f)] = find(it->second);
    }
  Pieces pieces;
  pieces.of_face.assign(mesh.face_count, -1);
  pieces.of_vertex.resize(mesh.vertex_count);
  std::map<size_t, int32_t> number;
  for (size_t f = 0; f < face_count; ++f) {
    const auto [it, added] = number.emplace(find(f), static_cast<int32_t>(number.size()));
    const auto source = static_cast<size_t>(prepared.face_sources[f]);
    // A two-sided sheet's mirror lies in its front's piece.
    const int32_t mirror = prepared.mirror_sources.empty() ? -1 : prepared.mirror_sources[f];
    for (const size_t face : {source, static_cast<size_t>(mirror)}) {
      if (face == static_cast<size_t>(-1)) continue;
      pieces.of_face[face] = it->second;
      for (size_t k = 0; k < 3; ++k) pieces.of_vertex[static_cast<size_t>(mesh.faces[3 * face + k])].push_back(it->second);
    }
  }
  pieces.count = number.size();
  return pieces;
}

void check_result(const animlod::fuzz::FuzzMesh& mesh, const animlod::AqemVertexData& data,
                  const std::vector<uint8_t>& locked, size_t level_count, bool weld, const animlod::AqemResult& result) {
  ANIMLOD_FUZZ_REQUIRE(result.levels.size() == level_count);
  const Pieces pieces = engine_pieces(mesh, data, weld);
  ANIMLOD_FUZZ_REQUIRE(result.vertex_weights.size() == mesh.vertex_count);
  for (int32_t f : result.frames_used) ANIMLOD_FUZZ_REQUIRE(f >= 0 && static_cast<size_t>(f) < mesh.frame_count);
  size_t previous_target = mesh.face_count;
  for (const animlod::AqemLevel& level : result.levels) {
    ANIMLOD_FUZZ_REQUIRE(level.target_face_count <= previous_target);
    previous_target = level.target_face_count;
    const size_t kept = level.kept_vertices.size();
    ANIMLOD_FUZZ_REQUIRE(level.faces.size() % 3 == 0);
    if (level.reached) ANIMLOD_FUZZ_REQUIRE(level.faces.size() / 3 <= level.target_face_count);
    for (int32_t index : level.faces) ANIMLOD_FUZZ_REQUIRE(index >= 0 && static_cast<size_t>(index) < kept);
    for (size_t i = 0; i < kept; ++i) {
      ANIMLOD_FUZZ_REQUIRE(level.kept_vertices[i] >= 0 && static_cast<size_t>(level.kept_vertices[i]) < mesh.vertex_count);
      if (i) ANIMLOD_FUZZ_REQUIRE(level.kept_vertices[i - 1] < level.kept_vertices[i]);
    }
    ANIMLOD_FUZZ_REQUIRE(level.face_sources.size() == level.faces.size() / 3);
    ANIMLOD_FUZZ_REQUIRE(level.vertex_map.size() == mesh.vertex_count);
    // -1 only where aqem.hpp says: no kept face uses the vertex (unreferenced, or only in faces
    // dropped as degenerate or repeated), or every piece with a corner of it collapsed away.
    std::vector<uint8_t> piece_alive(pieces.count, 0);
    for (int32_t source : level.face_sources)
      if (source >= 0 && static_cast<size_t>(source) < mesh.face_count && pieces.of_face[static_cast<size_t>(source)] >= 0)
        piece_alive[static_cast<size_t>(pieces.of_face[static_cast<size_t>(source)])] = 1;
    for (size_t v = 0; v < mesh.vertex_count; ++v) {
      const int32_t target = level.vertex_map[v];
      if (target >= 0) {
        ANIMLOD_FUZZ_REQUIRE(static_cast<size_t>(target) < kept);
        continue;
      }
      for (int32_t piece : pieces.of_vertex[v]) ANIMLOD_FUZZ_REQUIRE(!piece_alive[static_cast<size_t>(piece)]);
    }
    for (int32_t source : level.face_sources) {
      ANIMLOD_FUZZ_REQUIRE(source >= 0 && static_cast<size_t>(source) < mesh.face_count);
      for (int k = 0; k < 3; ++k)  // the corners of a face that survives are in the level
        ANIMLOD_FUZZ_REQUIRE(level.vertex_map[static_cast<size_t>(mesh.faces[3 * static_cast<size_t>(source) + k])] >= 0);
    }
    ANIMLOD_FUZZ_REQUIRE(level.positions.size() == mesh.frame_count * kept * 3);
    for (float value : level.positions) ANIMLOD_FUZZ_REQUIRE(std::isfinite(value));
    ANIMLOD_FUZZ_REQUIRE(level.attributes.size() == kept * data.attribute_count);
    ANIMLOD_FUZZ_REQUIRE(level.position_attributes.size() == kept * data.position_attribute_count);
    if (data.skin_joints) {
      const size_t k_count = data.influence_count;
      ANIMLOD_FUZZ_REQUIRE(level.skin_weights.size() == kept * k_count && level.skin_joints.size() == kept * k_count);
    }
    // A locked vertex that a face uses stays where it was, in every frame (it may be welded
    // onto a copy, which has its positions in every frame).
    for (size_t v = 0; v < locked.size(); ++v) {
      if (!(locked[v] & 1u) || level.vertex_map[v] < 0) continue;  // -1 checked above
      const auto i = static_cast<size_t>(level.vertex_map[v]);
      for (size_t f = 0; f < mesh.frame_count; ++f)
        for (int c = 0; c < 3; ++c)
          ANIMLOD_FUZZ_REQUIRE(level.positions[(f * kept + i) * 3 + c] ==
                               mesh.frames[(f * mesh.vertex_count + v) * 3 + c]);
    }
  }
  const size_t collapses = result.collapses.removed.size();
  ANIMLOD_FUZZ_REQUIRE(result.collapses.kept.size() == collapses && result.collapses.error.size() == collapses);
  ANIMLOD_FUZZ_REQUIRE(result.collapses.positions.size() == collapses * mesh.frame_count * 3);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  animlod::fuzz::FuzzInput in(data, size);
  const uint8_t flags = in.take<uint8_t>();
  const uint8_t flags2 = in.take<uint8_t>();
  const size_t level_count = 1 + in.take<uint8_t>() % 4;
  uint8_t level_bytes[4];
  for (uint8_t& byte : level_bytes) byte = in.take<uint8_t>();
  const uint8_t max_frames = in.take<uint8_t>();
  const uint8_t max_error = in.take<uint8_t>();
  const uint8_t threshold = in.take<uint8_t>();
  const uint8_t counts = in.take<uint8_t>();
  const size_t attribute_count = counts & 3u;
  const size_t position_attribute_count = (counts >> 3) & 3u;
  const size_t influences = 1 + in.take<uint8_t>() % 8;
  const animlod::fuzz::FuzzMesh mesh = animlod::fuzz::decode_mesh(in);
  const size_t vertex_count = mesh.vertex_count;

  animlod::AqemOptions options;
  options.use_motion_features = in.flag(flags, 0);
  options.boundary_quadrics = in.flag(flags, 1);
  options.check_inversion = in.flag(flags, 2);
  if (in.flag(flags, 3)) options.fold_limit = 0.0;
  options.motion_features.boundary_is_feature = in.flag(flags, 4);
  options.motion_features.feature_threshold = threshold / 64.0;
  options.placement = in.flag(flags, 5) ? animlod::Placement::on_edge : animlod::Placement::optimal;
  options.weld = !in.flag(counts, 2);
  options.tip_quadrics = !in.flag(counts, 5);
  options.max_frames = max_frames;
  if (in.flag(flags2, 4)) options.max_error = max_error / 16.0;
  options.target_ratios.clear();
  for (size_t level = 0; level < level_count; ++level) {
    if (in.flag(flags2, 2))
      options.target_face_counts.push_back(level_bytes[level] * mesh.face_count / 255);
    else
      options.target_ratios.push_back(level_bytes[level] / 255.0);
  }
  if (in.flag(flags2, 5))
    options.progress = [](size_t done, size_t) {
      if (done > 0) throw std::runtime_error("progress callback stops the run");
    };

  animlod::AqemVertexData vertex_data;
  std::vector<uint8_t> locked;
  std::vector<float> importance, attributes, skin_weights, position_attributes;
  std::vector<int32_t> skin_joints, face_groups;
  if (in.flag(flags, 6)) {
    locked.resize(vertex_count);
    for (uint8_t& value : locked) value = in.take<uint8_t>() & 1u;
    vertex_data.locked = locked.data();
  }
  if (in.flag(flags, 7)) {
    importance.resize(vertex_count);
    for (float& value : importance) value = in.take<uint8_t>() / 16.0f;
    vertex_data.importance = importance.data();
  }
  if (in.flag(flags2, 0) && attribute_count) {
    attributes.resize(vertex_count * attribute_count);
    for (float& value : attributes) value = in.coordinate(false);
    vertex_data.attributes = attributes.data();
    vertex_data.attribute_count = attribute_count;
  }
  if (in.flag(flags2, 1)) {
    skin_joints.resize(vertex_count * influences);
    skin_weights.resize(vertex_count * influences);
    for (size_t i = 0; i < skin_joints.size(); ++i) {
      const uint8_t joint = in.take<uint8_t>();
      const uint8_t weight = in.take<uint8_t>();
      skin_joints[i] = joint == 255 ? -1 : joint;
      skin_weights[i] = weight == 254 ? std::nanf("") : weight / 255.0f;
    }
    vertex_data.skin_joints = skin_joints.data();
    vertex_data.skin_weights = skin_weights.data();
    vertex_data.influence_count = influences;
  }
  if (in.flag(flags2, 3)) {
    const size_t count = in.take<uint8_t>() % 8;
    for (size_t i = 0; i < count; ++i) options.frame_subset.push_back(in.take<uint8_t>() % (mesh.frame_count + 2));
  }

  if (in.flag(flags2, 6) && position_attribute_count) {
    position_attributes.resize(vertex_count * position_attribute_count);
    for (float& value : position_attributes) value = in.coordinate(false);
    vertex_data.position_attributes = position_attributes.data();
    vertex_data.position_attribute_count = position_attribute_count;
  }
  if (in.flag(flags2, 7)) {
    face_groups.resize(mesh.face_count);
    for (int32_t& group : face_groups) group = in.take<uint8_t>() % 4;
    vertex_data.face_groups = face_groups.data();
  }

  animlod::AqemResult result;
  animlod::Status status;
  try {
    status = animlod::simplify_animated(mesh.view(), vertex_data, options, result);
  } catch (const std::runtime_error&) {
    // Only the progress callback throws; the header promises `out` is then left empty.
    ANIMLOD_FUZZ_REQUIRE(in.flag(flags2, 5) && result.levels.empty());
    return 0;
  }
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty() && result.levels.empty());
    return 0;
  }
  check_result(mesh, vertex_data, locked, level_count, options.weld, result);
  return 0;
}
