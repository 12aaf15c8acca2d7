// Morph weight tracks of the crowd (morph_weights.hpp): glTF's T weights a key, split into the
// core's tracks of up to 4, sample as one track of T would, in each interpolation, and are
// sampled again only when the pose they are drawn with moves.
#include <doctest/doctest.h>

#include <initializer_list>
#include <string>
#include <vector>

#include "morph_weights.hpp"

namespace {

using animlod::Interpolation;
using crowd::MorphWeightsTrack;

// Samples a track of 5 weights (two groups: 4 and 1) with keys at 0 and 1 s at `time`.
std::vector<float> sample(Interpolation interpolation, const std::vector<float>& values, float time) {
  MorphWeightsTrack track;
  std::string error;
  REQUIRE(MorphWeightsTrack::make({0.0f, 1.0f}, values, 5, interpolation, track, error));
  std::vector<float> out(5, -1.0f);
  track.sample(time, out.data());
  return out;
}

const std::vector<float> kFirst{0, 1, 2, 3, 4}, kSecond{10, 11, 12, 13, 14};

std::vector<float> joined(std::initializer_list<std::vector<float>> parts) {
  std::vector<float> out;
  for (const std::vector<float>& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

}  // namespace

TEST_CASE("crowd morph weights: every target sampled in each interpolation, across the groups of 4") {
  const std::vector<float> keys = joined({kFirst, kSecond});
  CHECK(sample(Interpolation::linear, keys, 0.5f) == std::vector<float>{5, 6, 7, 8, 9});
  CHECK(sample(Interpolation::step, keys, 0.5f) == kFirst);
  CHECK(sample(Interpolation::linear, keys, 3.0f) == kSecond);  // the last key holds
  // (in-tangent, value, out-tangent) a key: the first key's out-tangent 8 adds 8 / 8 at s = 0.5;
  // the tangents that do not bound the span (100) are not read.
  const std::vector<float> hundred(5, 100.0f), eight(5, 8.0f), zero(5, 0.0f);
  const std::vector<float> cubic = joined({hundred, kFirst, eight, zero, kSecond, hundred});
  CHECK(sample(Interpolation::cubic_spline, cubic, 0.5f) == std::vector<float>{6, 7, 8, 9, 10});
}

TEST_CASE("crowd morph weights: outputs of another size are refused, and the keys bound the weights played") {
  MorphWeightsTrack track;
  std::string error;
  CHECK_FALSE(MorphWeightsTrack::make({0.0f, 1.0f}, {0, 1, 2}, 2, Interpolation::linear, track, error));
  CHECK(error == "output holds 3 numbers for 2 keys of 2 morph weights");
  CHECK_FALSE(MorphWeightsTrack::make({1.0f, 0.0f}, {0, 1}, 1, Interpolation::linear, track, error));
  CHECK(error.find("morph weights 0 to 0: ") == 0);  // the core's message follows: times must increase
  crowd::MorphPlayback playback;
  playback.defaults = {0.5f, -2.0f};
  REQUIRE(MorphWeightsTrack::make({0.0f, 1.0f}, {1, 0, -3, 1}, 2, Interpolation::linear, track, error));
  playback.tracks = {MorphWeightsTrack(), track};
  CHECK(playback.keyed_weights() == std::vector<std::vector<float>>{{0.5f, -2.0f}, {1, 0}, {-3, 1}});
  std::vector<float> weights(2);
  playback.sample(0, 0.5f, weights.data());  // a clip without a weights channel: the defaults
  CHECK(weights == playback.defaults);
  playback.sample(1, 0.5f, weights.data());
  CHECK(weights == std::vector<float>{-1, 0.5f});
}

TEST_CASE("crowd morph weights follow the pose: held on the frames it is held, sampled when it moves or the level changes") {
  // They were sampled every frame, also on frames that frame skipping held the pose (and the clip time) on.
  CHECK_FALSE(crowd::morph_weights_due(false, 1, 1));
  CHECK(crowd::morph_weights_due(true, 1, 1));
  CHECK(crowd::morph_weights_due(false, 1, 2));   // another level: its own weights at its skeleton's clip time
  CHECK(crowd::morph_weights_due(false, -1, 0));  // none sampled yet
}
