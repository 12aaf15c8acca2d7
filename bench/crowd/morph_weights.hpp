// Morph weights a clip plays on a level node (glTF animation channels with path "weights"),
// sampled on the CPU by the core's keyframe sampler like the joints' channels (LINEAR, STEP,
// CUBICSPLINE) and added on the GPU per instance (gl_renderer.cpp).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "animlod/pose.hpp"

namespace crowd {

// One "weights" channel: T weights a key, kept as tracks of up to 4 of them (the core's
// KeyframeTrack takes 1 to 4 components).
class MorphWeightsTrack {
 public:
  MorphWeightsTrack() = default;

  // `times` (N,) seconds; `values` as glTF stores them, (N, T) or (N, 3, T) for cubic_spline (in-
  // tangents, values, out-tangents). False with `error` when the sizes disagree or
  // animlod::validate_track refuses a group of targets (its message, naming the key).
  static bool make(std::vector<float> times, const std::vector<float>& values, size_t target_count,
                   animlod::Interpolation interpolation, MorphWeightsTrack& out, std::string& error);

  bool empty() const { return times_.empty(); }
  float duration() const { return times_.empty() ? 0.0f : times_.back(); }
  // The T weights at `time` (seconds) into out (T,).
  void sample(float time, float* out) const;
  // Appends the T weights of each key to `out`.
  void append_keys(std::vector<std::vector<float>>& out) const;

 private:
  std::vector<float> times_;
  std::vector<std::vector<float>> groups_;  // per 4 targets: (N, c) or (N, 3, c), c <= 4
  size_t target_count_ = 0;
  animlod::Interpolation interpolation_ = animlod::Interpolation::linear;

  animlod::KeyframeTrack group_track(size_t group) const;
};

// The morph weights a level node plays on the GPU: per original clip the node's "weights"
// channel, or its default weights where that clip has none (a channel animates one node).
struct MorphPlayback {
  std::vector<float> defaults;            // (T,) the node's weights, else its mesh's, else zeros
  std::vector<MorphWeightsTrack> tracks;  // per original clip; empty: defaults
  size_t target_count() const { return defaults.size(); }
  // The weights of original clip `clip` at `time` into out (T,).
  void sample(size_t clip, float time, float* out) const;
  // The defaults and every key of every clip, (T,) each: the weights between keys blend them
  // (LINEAR, STEP; CUBICSPLINE may overshoot a little).
  std::vector<std::vector<float>> keyed_weights() const;
};

// Whether a chain's morph weights are sampled this frame. They depend on the level drawn and its
// skeleton's clip time, which only a pose update changes: they are sampled when the pose was
// updated or the chain draws another level than the one they were sampled for (-1: none yet),
// and held with the pose on the frames that frame skipping skips.
inline bool morph_weights_due(bool pose_updated, int sampled_level, int drawn_level) {
  return pose_updated || sampled_level != drawn_level;
}

}  // namespace crowd
