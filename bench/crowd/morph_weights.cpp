// Morph weight tracks of the crowd (morph_weights.hpp): glTF's (N, T) weights split into groups
// of 4 targets so that the core's sample_track plays them as it plays the joints' channels.
#include "morph_weights.hpp"

#include <algorithm>

namespace crowd {

namespace {

constexpr size_t kGroup = 4;  // KeyframeTrack's largest component count

}  // namespace

bool MorphWeightsTrack::make(std::vector<float> times, const std::vector<float>& values, size_t target_count,
                             animlod::Interpolation interpolation, MorphWeightsTrack& out, std::string& error) {
  const size_t keys = times.size();
  const size_t per_key = interpolation == animlod::Interpolation::cubic_spline ? 3 : 1;  // in-tangent, value, out-tangent
  if (target_count == 0 || values.size() != keys * per_key * target_count) {
    error = "output holds " + std::to_string(values.size()) + " numbers for " + std::to_string(keys) + " keys of " +
            std::to_string(target_count) + " morph weights";
    return false;
  }
  MorphWeightsTrack track;
  track.times_ = std::move(times);
  track.target_count_ = target_count;
  track.interpolation_ = interpolation;
  for (size_t first = 0; first < target_count; first += kGroup) {
    const size_t width = std::min(kGroup, target_count - first);
    std::vector<float> group;
    group.reserve(keys * per_key * width);
    for (size_t row = 0; row < keys * per_key; ++row)
      group.insert(group.end(), values.begin() + static_cast<std::ptrdiff_t>(row * target_count + first),
                   values.begin() + static_cast<std::ptrdiff_t>(row * target_count + first + width));
    track.groups_.push_back(std::move(group));
    const animlod::Status status = animlod::validate_track(track.group_track(track.groups_.size() - 1), false);
    if (!status) {
      error = "morph weights " + std::to_string(first) + " to " + std::to_string(first + width - 1) + ": " + status.message;
      return false;
    }
  }
  out = std::move(track);
  return true;
}

animlod::KeyframeTrack MorphWeightsTrack::group_track(size_t group) const {
  animlod::KeyframeTrack track;
  track.times = times_.data();
  track.values = groups_[group].data();
  track.key_count = times_.size();
  track.component_count = std::min(kGroup, target_count_ - group * kGroup);
  track.interpolation = interpolation_;
  return track;
}

void MorphWeightsTrack::sample(float time, float* out) const {
  for (size_t group = 0; group < groups_.size(); ++group)
    animlod::sample_track(group_track(group), time, false, animlod::RotationBlend::nlerp, out + group * kGroup);
}

void MorphWeightsTrack::append_keys(std::vector<std::vector<float>>& out) const {
  const size_t per_key = interpolation_ == animlod::Interpolation::cubic_spline ? 3 : 1;
  for (size_t key = 0; key < times_.size(); ++key) {
    std::vector<float> weights(target_count_);
    for (size_t group = 0; group < groups_.size(); ++group) {
      const size_t width = std::min(kGroup, target_count_ - group * kGroup);
      const float* value = groups_[group].data() + (key * per_key + per_key / 2) * width;  // the value, not a tangent
      std::copy(value, value + width, weights.begin() + static_cast<std::ptrdiff_t>(group * kGroup));
    }
    out.push_back(std::move(weights));
  }
}

void MorphPlayback::sample(size_t clip, float time, float* out) const {
  if (clip < tracks.size() && !tracks[clip].empty()) tracks[clip].sample(time, out);
  else std::copy(defaults.begin(), defaults.end(), out);
}

std::vector<std::vector<float>> MorphPlayback::keyed_weights() const {
  std::vector<std::vector<float>> out{defaults};
  for (const MorphWeightsTrack& track : tracks) track.append_keys(out);
  return out;
}

}  // namespace crowd
