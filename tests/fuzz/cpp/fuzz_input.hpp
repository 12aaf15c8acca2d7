// Structure-aware decoding of fuzz bytes into the arrays the core's entry points take.
//
// libFuzzer mutates bytes; a harness reads sizes, indices and floats from them with FuzzInput,
// so that a mutation changes one count, one index or one coordinate rather than shifting every
// later array. Reading past the end yields zeros (a short input is still a valid input).
//
// The layout of an animated mesh (decode_mesh), mirrored by tests/fuzz/seeds.py, which encodes
// real meshes as seeds; all integers little-endian:
//   u8  mode       bit 0: coordinates are raw float32 bits (NaN and inf possible), else int16 / 64
//   u16 frames     F = 1 + value % kMaxFrames
//   u16 vertices   V = 1 + value % kMaxVertices, then lowered to what the bytes left can fill
//   u16 faces      M = value % (kMaxFaces + 1), lowered likewise
//   F * V * 3 coordinates, then M * 3 vertex indices (u16, see index())
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "animlod/animated_mesh_view.hpp"

namespace animlod::fuzz {

constexpr size_t kMaxFrames = 16;
constexpr size_t kMaxVertices = 4096;
constexpr size_t kMaxFaces = 8192;
// u16 index values from here up decode to indices outside [0, n) (see FuzzInput::index).
constexpr uint16_t kFirstSpecialIndex = 0xFFF8;

class FuzzInput {
 public:
  FuzzInput(const uint8_t* data, size_t size) : data_(data), size_(size) {}

  size_t remaining() const { return size_ - position_; }

  // The next sizeof(T) bytes as a little-endian T; zero bytes past the end.
  template <typename T>
  T take() {
    unsigned char bytes[sizeof(T)] = {};
    const size_t n = remaining() < sizeof(T) ? remaining() : sizeof(T);
    if (n) std::memcpy(bytes, data_ + position_, n);
    position_ += n;
    T value;
    std::memcpy(&value, bytes, sizeof(T));
    return value;
  }

  bool flag(uint8_t bits, int bit) const { return (bits >> bit) & 1u; }

  // A coordinate: raw float32 bits, or an int16 step of 1/64 (dense, finite, exact in float).
  float coordinate(bool raw) { return raw ? take<float>() : static_cast<float>(take<int16_t>()) / 64.0f; }

  // A vertex or joint index for a set of n: value % n, except the eight top u16 values, which
  // give indices just outside the range or at the ends of int32.
  int32_t index(size_t n) {
    const uint16_t value = take<uint16_t>();
    if (value < kFirstSpecialIndex) return n ? static_cast<int32_t>(value % n) : 0;
    const int32_t special[] = {-1, static_cast<int32_t>(n), static_cast<int32_t>(n + 1), -2,
                               std::numeric_limits<int32_t>::max(), std::numeric_limits<int32_t>::min(),
                               static_cast<int32_t>(2 * n), 0x7FFF};
    return special[value - kFirstSpecialIndex];
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t position_ = 0;
};

// An animated mesh owning its arrays; view() is what the core takes.
struct FuzzMesh {
  std::vector<float> frames;   // (F, V, 3)
  std::vector<int32_t> faces;  // (M, 3)
  size_t frame_count = 0, vertex_count = 0, face_count = 0;

  AnimatedMeshView view() const {
    return AnimatedMeshView{frames.data(), faces.data(), frame_count, vertex_count, face_count};
  }
};

// Reads the mesh layout of the header comment.
inline FuzzMesh decode_mesh(FuzzInput& in) {
  FuzzMesh mesh;
  const bool raw = in.take<uint8_t>() & 1u;
  mesh.frame_count = 1 + in.take<uint16_t>() % kMaxFrames;
  size_t vertices = 1 + in.take<uint16_t>() % kMaxVertices;
  size_t faces = in.take<uint16_t>() % (kMaxFaces + 1);
  const size_t coordinate_bytes = raw ? 4 : 2;
  // Never more than the bytes can fill (at least one vertex and, when asked, one face).
  const size_t vertex_fit = in.remaining() / (mesh.frame_count * 3 * coordinate_bytes);
  mesh.vertex_count = vertices < vertex_fit ? vertices : (vertex_fit ? vertex_fit : 1);
  const size_t left = in.remaining() > mesh.frame_count * mesh.vertex_count * 3 * coordinate_bytes
                          ? in.remaining() - mesh.frame_count * mesh.vertex_count * 3 * coordinate_bytes
                          : 0;
  const size_t face_fit = left / 6;
  mesh.face_count = faces < face_fit ? faces : (faces ? (face_fit ? face_fit : 1) : 0);
  mesh.frames.resize(mesh.frame_count * mesh.vertex_count * 3);
  for (float& value : mesh.frames) value = in.coordinate(raw);
  mesh.faces.resize(mesh.face_count * 3);
  for (int32_t& index : mesh.faces) index = in.index(mesh.vertex_count);
  return mesh;
}

// A broken invariant: print it and abort, which libFuzzer records as a crash.
[[noreturn]] inline void invariant_failed(const char* file, int line, const char* what) {
  std::fprintf(stderr, "%s:%d: invariant broken: %s\n", file, line, what);
  std::abort();
}

}  // namespace animlod::fuzz

#define ANIMLOD_FUZZ_REQUIRE(condition) \
  ((condition) ? (void)0 : ::animlod::fuzz::invariant_failed(__FILE__, __LINE__, #condition))
