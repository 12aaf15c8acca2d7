// Skin weights of a vertex made by merging two: the union of their influences, blended with
// the collapse parameter, the K largest kept and renormalised (glTF-style top-K skinning).
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace animlod::detail {

// keep_*/remove_* are K-long rows; the result (written over keep_*) is sorted by decreasing
// weight (ties by joint), sums to 1, and pads unused slots with joint 0 and weight 0.
inline void merge_skin_weights(int32_t* keep_joints, float* keep_weights, const int32_t* remove_joints,
                               const float* remove_weights, size_t influence_count, double t) {
  std::vector<std::pair<int32_t, double>> merged;
  merged.reserve(2 * influence_count);
  auto add = [&merged](int32_t joint, double weight) {
    if (weight <= 0.0) return;
    for (auto& entry : merged)
      if (entry.first == joint) {
        entry.second += weight;
        return;
      }
    merged.emplace_back(joint, weight);
  };
  for (size_t k = 0; k < influence_count; ++k) add(keep_joints[k], (1.0 - t) * keep_weights[k]);
  for (size_t k = 0; k < influence_count; ++k) add(remove_joints[k], t * remove_weights[k]);
  std::sort(merged.begin(), merged.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
  if (merged.size() > influence_count) merged.resize(influence_count);
  double total = 0.0;
  for (const auto& entry : merged) total += entry.second;
  if (total <= 0.0) return;  // both rows empty: nothing to blend
  for (size_t k = 0; k < influence_count; ++k) {
    const bool used = k < merged.size();
    keep_joints[k] = used ? merged[k].first : 0;
    keep_weights[k] = used ? static_cast<float>(merged[k].second / total) : 0.0f;
  }
}

}  // namespace animlod::detail
