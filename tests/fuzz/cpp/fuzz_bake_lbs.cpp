// Fuzz harness: bake_lbs. Input (little-endian):
//   u8  mode         bit 0: raw float32 positions and matrices, else int16 / 64
//   u16 vertices     V = value % 2049
//   u8  influences   K = 1 + value % 8
//   u8  joints       J = 1 + value % 64
//   u8  frames       T = 1 + value % 16
//   (V, then J and T, lowered to what the bytes left can fill, as in decode_mesh)
//   V * 3 rest coordinates; V * K joint indices (u16, FuzzInput::index over J); V * K weights
//   (u8: value / 255, except 255 -> NaN, 254 -> inf, 253 -> -1); T * J * 16 matrix entries.
// Invariants: an error has a message and comes from a bad joint index or weight; on success
// with every input finite and small (int16 mode) every output is finite. skin_distance_maxima
// of the skin against itself fails alike, and is 0 in a frame of finite positions, else NaN.
#include <cmath>
#include <limits>
#include <vector>

#include "animlod/skinning.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  animlod::fuzz::FuzzInput in(data, size);
  const bool raw = in.take<uint8_t>() & 1u;
  const size_t coordinate_bytes = raw ? 4 : 2;
  size_t vertex_count = in.take<uint16_t>() % 2049;
  const size_t influences = 1 + in.take<uint8_t>() % 8;
  size_t joint_count = 1 + in.take<uint8_t>() % 64;
  size_t frame_count = 1 + in.take<uint8_t>() % 16;
  // Each vertex takes 3 coordinates and K (index, weight) pairs; each matrix 16 entries.
  const size_t per_vertex = 3 * coordinate_bytes + 3 * influences;
  if (vertex_count > in.remaining() / per_vertex) vertex_count = in.remaining() / per_vertex;
  const size_t matrix_bytes = in.remaining() - vertex_count * per_vertex;
  const size_t matrices_fit = matrix_bytes / (16 * coordinate_bytes);
  if (joint_count > matrices_fit) joint_count = matrices_fit ? matrices_fit : 1;
  if (frame_count * joint_count > matrices_fit) frame_count = matrices_fit / joint_count ? matrices_fit / joint_count : 1;
  std::vector<float> rest(vertex_count * 3);
  for (float& value : rest) value = in.coordinate(raw);
  std::vector<int32_t> joints(vertex_count * influences);
  for (int32_t& joint : joints) joint = in.index(joint_count);
  std::vector<float> weights(vertex_count * influences);
  bool inputs_valid = true;
  for (size_t i = 0; i < weights.size(); ++i) {
    const uint8_t byte = in.take<uint8_t>();
    weights[i] = byte == 255   ? std::numeric_limits<float>::quiet_NaN()
                 : byte == 254 ? std::numeric_limits<float>::infinity()
                 : byte == 253 ? -1.0f
                               : byte / 255.0f;
    inputs_valid = inputs_valid && std::isfinite(weights[i]) && joints[i] >= 0 &&
                   static_cast<size_t>(joints[i]) < joint_count;
  }
  std::vector<float> matrices(frame_count * joint_count * 16);
  for (float& value : matrices) value = in.coordinate(raw);

  animlod::SkinningInput input;
  input.rest_positions = rest.data();
  input.joints = joints.data();
  input.weights = weights.data();
  input.skin_matrices = matrices.data();
  input.vertex_count = vertex_count;
  input.influence_count = influences;
  input.joint_count = joint_count;
  input.frame_count = frame_count;
  std::vector<float> out(frame_count * vertex_count * 3);
  const animlod::Status status = animlod::bake_lbs(input, out.data());
  ANIMLOD_FUZZ_REQUIRE(status.ok == inputs_valid);
  // The skin against itself: the same errors; each frame's largest distance 0, or NaN where a
  // position is not finite (inf - inf), as numpy's max keeps a NaN.
  std::vector<float> maxima(frame_count);
  const animlod::Status self = animlod::skin_distance_maxima(input, &input, 1, maxima.data());
  ANIMLOD_FUZZ_REQUIRE(self.ok == status.ok);
  for (size_t t = 0; status && t < frame_count; ++t) {
    bool finite = true;
    for (size_t i = 3 * t * vertex_count; i < 3 * (t + 1) * vertex_count; ++i)
      finite = finite && std::isfinite(out[i]);
    ANIMLOD_FUZZ_REQUIRE(finite ? maxima[t] == 0.0f : std::isnan(maxima[t]));
  }
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
    return 0;
  }
  if (!raw) {
    // |entries| <= 512, |weights| <= 1, K <= 8: every output is far inside float range.
    bool weights_bounded = true;
    for (float w : weights) weights_bounded = weights_bounded && std::fabs(w) <= 1.0f;
    if (weights_bounded)
      for (float value : out) ANIMLOD_FUZZ_REQUIRE(std::isfinite(value));
  }
  return 0;
}
