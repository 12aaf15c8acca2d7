// Fuzz harness: compute_motion_features. Input: u8 flags (bit 0 boundary_is_feature, bit 1 the
// paper's weighting instead of amplitude), u8
// feature_threshold (value / 64 radians), u8 min_angle_change (value / 256 radians), then the
// mesh layout of fuzz_input.hpp.
// Invariants on success: edges sorted with the lower vertex first; one angle change, finite and
// >= 0, per edge; every vertex's feature index in [-1, C); feature sizes add up to the vertices
// in features; vertex weights >= 1; amplitude weighting: amplitudes finite and >= 0, weights at
// most max_feature_weight and exactly 1 outside every feature.
#include <cmath>

#include "animlod/motion_features.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  animlod::fuzz::FuzzInput in(data, size);
  animlod::MotionFeatureOptions options;
  const uint8_t flags = in.take<uint8_t>();
  options.boundary_is_feature = in.flag(flags, 0);
  if (in.flag(flags, 1)) options.feature_weighting = animlod::FeatureWeighting::paper;
  options.feature_threshold = in.take<uint8_t>() / 64.0;
  options.min_angle_change = in.take<uint8_t>() / 256.0;
  const animlod::fuzz::FuzzMesh mesh = animlod::fuzz::decode_mesh(in);
  animlod::MotionFeatures out;
  const animlod::Status status = animlod::compute_motion_features(mesh.view(), options, out);
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
    return 0;
  }
  const size_t edge_count = out.angle_change.size();
  ANIMLOD_FUZZ_REQUIRE(out.edges.size() == 2 * edge_count && out.connected.size() == edge_count);
  for (size_t e = 0; e < edge_count; ++e) {
    ANIMLOD_FUZZ_REQUIRE(out.edges[2 * e] < out.edges[2 * e + 1]);
    ANIMLOD_FUZZ_REQUIRE(out.edges[2 * e + 1] < static_cast<int32_t>(mesh.vertex_count));
    if (e) {
      const bool ascending = out.edges[2 * e - 2] < out.edges[2 * e] ||
                             (out.edges[2 * e - 2] == out.edges[2 * e] && out.edges[2 * e - 1] < out.edges[2 * e + 1]);
      ANIMLOD_FUZZ_REQUIRE(ascending);
    }
    ANIMLOD_FUZZ_REQUIRE(std::isfinite(out.angle_change[e]) && out.angle_change[e] >= 0.0f);
    ANIMLOD_FUZZ_REQUIRE(std::isfinite(out.amplitude[e]) && out.amplitude[e] >= 0.0f);
  }
  ANIMLOD_FUZZ_REQUIRE(out.vertex_feature.size() == mesh.vertex_count && out.vertex_weights.size() == mesh.vertex_count);
  const auto feature_count = static_cast<int32_t>(out.feature_sizes.size());
  size_t in_features = 0, total = 0;
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    ANIMLOD_FUZZ_REQUIRE(out.vertex_feature[v] >= -1 && out.vertex_feature[v] < feature_count);
    ANIMLOD_FUZZ_REQUIRE(out.vertex_weights[v] >= 1.0f);
    if (options.feature_weighting == animlod::FeatureWeighting::amplitude) {
      ANIMLOD_FUZZ_REQUIRE(out.vertex_weights[v] <= static_cast<float>(options.max_feature_weight));
      ANIMLOD_FUZZ_REQUIRE(out.vertex_feature[v] >= 0 || out.vertex_weights[v] == 1.0f);
    }
    in_features += out.vertex_feature[v] >= 0;
  }
  for (int32_t w : out.feature_sizes) total += static_cast<size_t>(w);
  ANIMLOD_FUZZ_REQUIRE(total == in_features);
  return 0;
}
