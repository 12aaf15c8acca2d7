// Per-frame culling, level selection, frame skipping and posing of the crowd, and the gather of
// palettes and instances (crowd_animation.hpp; seeds/000 Section 3, seeds/004 Section 4.2.3).
#include "crowd_animation.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace crowd {

namespace {

// Floats of `count` values in whole RGBA32F texels.
size_t padded_to_texels(size_t count) { return (count + 3) / 4 * 4; }

}  // namespace

CrowdAnimator::CrowdAnimator(const std::vector<Asset>& assets, const CrowdScene& scene, const CrowdOptions& options)
    : assets_(assets), scene_(scene), options_(options) {
  size_t most_floats = 0, most_chains = 0;
  bucket_base_.resize(assets.size());
  rig_clips_.resize(assets.size());
  for (size_t a = 0; a < assets.size(); ++a) {
    // Any level using a rig maps the original clips to that rig's clips the same way.
    rig_clips_[a].assign(assets[a].rigs.size(), nullptr);
    for (const Chain& chain : assets[a].chains)
      for (const Level& level : chain.levels)
        if (!rig_clips_[a][static_cast<size_t>(level.rig)]) rig_clips_[a][static_cast<size_t>(level.rig)] = &level.clips;
    // A character draws one level per chain: at most one skeleton and one set of weights each.
    size_t floats = 0;
    for (const Chain& chain : assets[a].chains) {
      size_t most = 0;
      for (const Level& level : chain.levels)
        most = std::max(most, 12 * assets[a].rigs[static_cast<size_t>(level.rig)].joint_count() +
                                  padded_to_texels(level.morph.target_count()));
      floats += most;
    }
    most_floats = std::max(most_floats, floats);
    most_chains = std::max(most_chains, assets[a].chains.size());
    for (size_t c = 0; c < assets[a].chains.size(); ++c) {
      bucket_base_[a].push_back(static_cast<int>(all_buckets_.size()));
      for (size_t l = 0; l < assets[a].chains[c].levels.size(); ++l) {
        Bucket bucket;
        bucket.asset = static_cast<int>(a);
        bucket.chain = static_cast<int>(c);
        bucket.level = static_cast<int>(l);
        all_buckets_.push_back(bucket);
      }
    }
  }
  const size_t count = scene.placements().size();
  max_buffer_floats_ = count * most_floats;
  max_instances_ = count * most_chains;
}

namespace {

// The level of `chain` drawing (mesh level g, motion level m), or where the chain has no such
// node the one with the most reduction that stays within both (level 0 at worst).
int nearest_level(const Chain& chain, int g, int m) {
  const int exact = chain.find(g, m);
  if (exact >= 0) return exact;
  int best = 0, best_reduction = -1;
  for (size_t l = 0; l < chain.levels.size(); ++l) {
    const Level& level = chain.levels[l];
    const int reduction = level.mesh_level + level.motion_level;
    if (level.mesh_level <= g && level.motion_level <= m && reduction > best_reduction) {
      best = static_cast<int>(l);
      best_reduction = reduction;
    }
  }
  return best;
}

// One motion level per skeleton: the chains of one skeleton (Chain::skeleton: the meshes of one
// character, a body and its eyes, BrainStem's parts) draw the finest motion level any of them
// chose, each at its own mesh level, so that a character poses one skeleton and not one per
// mesh (MLoD animated more joints than Original on such characters), and a part skinned to the
// body's head never follows another level's head.
void share_motion_levels(const Asset& asset, std::vector<int>& levels) {
  for (size_t c = 0; c < asset.chains.size(); ++c) {
    const Chain& chain = asset.chains[c];
    int finest = chain.levels[static_cast<size_t>(levels[c])].motion_level;
    for (size_t d = 0; d < asset.chains.size(); ++d)
      if (asset.chains[d].skeleton == chain.skeleton)
        finest = std::min(finest, asset.chains[d].levels[static_cast<size_t>(levels[d])].motion_level);
    const Level& chosen = chain.levels[static_cast<size_t>(levels[c])];
    if (finest < chosen.motion_level) levels[c] = nearest_level(chain, chosen.mesh_level, finest);
  }
}

}  // namespace

void CrowdAnimator::start(const Mode& mode, const int* forced) {
  mode_ = mode;
  frame_ = 0;
  subsets_.assign(assets_.size(), {});
  for (size_t a = 0; a < assets_.size(); ++a) {
    for (const Chain& chain : assets_[a].chains) {
      ChainSubset subset;
      for (size_t l = 0; l < chain.selection_count; ++l) {
        const Level& level = chain.levels[l];
        subset.errors.push_back(level.error);
        subset.coverages.push_back(level.coverage);
        subset.drawn.push_back(nearest_level(chain, mode.geometry_levels ? level.mesh_level : 0,
                                             mode.motion_levels ? level.motion_level : 0));
      }
      if (forced) subset.forced = nearest_level(chain, forced[0], forced[1]);
      subsets_[a].push_back(std::move(subset));
    }
  }
  animlod::LodSelectorOptions selector_options;
  selector_options.hysteresis = options_.hysteresis;
  selector_options.pixel_error = options_.pixel_error;
  characters_.assign(scene_.placements().size(), Character());
  for (size_t i = 0; i < characters_.size(); ++i) {
    const Asset& asset = assets_[static_cast<size_t>(scene_.placements()[i].asset)];
    characters_[i].selectors.assign(asset.chains.size(), animlod::LodSelector(selector_options));
    characters_[i].levels.assign(asset.chains.size(), 0);
    characters_[i].morph_weights.assign(asset.chains.size(), {});
    characters_[i].morph_levels.assign(asset.chains.size(), -1);
  }
}

CrowdAnimator::PoseCache& CrowdAnimator::cache_for(Character& character, int rig) {
  for (PoseCache& cache : character.caches)
    if (cache.rig == rig) return cache;
  character.caches.emplace_back();
  character.caches.back().rig = rig;
  return character.caches.back();
}

void CrowdAnimator::update_pose(const Asset& asset, const Placement& placement, int rig_index, float time,
                                PoseCache& cache) {
  const Rig& rig = asset.rigs[static_cast<size_t>(rig_index)];
  const size_t poses = rig.pose_count(), joints = rig.joint_count();
  translations_.assign(rig.rest_translations.begin(), rig.rest_translations.end());
  rotations_.assign(rig.rest_rotations.begin(), rig.rest_rotations.end());
  scales_.assign(rig.rest_scales.begin(), rig.rest_scales.end());
  world_.resize(16 * poses);
  palette_.resize(16 * joints);
  const std::vector<int>* clips = rig_clips_[static_cast<size_t>(placement.asset)][static_cast<size_t>(rig_index)];
  const Clip* clip = clips ? &asset.clips[static_cast<size_t>((*clips)[static_cast<size_t>(placement.clip)])] : nullptr;
  const animlod::LocalPose pose{translations_.data(), rotations_.data(), scales_.data(), poses};
  // A skipped frame keeps the last pose; an update samples the current time, so the clip keeps
  // its speed (the facial LoD paper's skipping changed the clip's duration).
  cache.clip_time = clip && clip->duration > 0.0f ? std::fmod(time + placement.phase, clip->duration) : 0.0f;
  if (clip) animlod::sample_clip(clip->view(), cache.clip_time, animlod::RotationBlend::nlerp, pose);
  // The rig's parents were validated at load (FK of the rest pose for the bounds).
  animlod::forward_kinematics(rig.parents.data(), pose, world_.data());
  animlod::skin_palette(world_.data(), rig.joint_nodes.data(), rig.inverse_bind.data(), joints, palette_.data());
  cache.rows.resize(12 * joints);
  for (size_t j = 0; j < joints; ++j) {
    const float* m = palette_.data() + 16 * j;  // column-major: m[4 * column + row]
    float* rows = cache.rows.data() + 12 * j;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) rows[4 * r + c] = m[4 * c + r];
  }
  cache.valid = true;
  cache.posed_frame = frame_;
}

void CrowdAnimator::animate(const Camera& camera, const animlod::LodCamera& lod_camera, uint64_t frame, float time,
                            FrameCounts& counts) {
  frame_ = frame;
  counts = FrameCounts();
  counts.levels.assign(16, 0);
  const float focal = animlod::focal_length_pixels(lod_camera);
  animlod::AnimationRateOptions rate;
  rate.full_rate_coverage = options_.skip_full_coverage;
  rate.max_interval = options_.skip_max_interval;
  const std::vector<Placement>& placements = scene_.placements();
  for (size_t i = 0; i < characters_.size(); ++i) {
    Character& character = characters_[i];
    const Placement& placement = placements[i];
    const Asset& asset = assets_[static_cast<size_t>(placement.asset)];
    const glm::vec3 center = placement.position + asset.sphere_center;  // yaw turns about the origin's vertical
    const float radius = asset.sphere_radius + glm::length(glm::vec2(asset.sphere_center.x, asset.sphere_center.z));
    character.was_visible = character.visible;
    character.visible = sphere_visible(camera, center, radius);
    if (!character.visible) continue;
    ++counts.drawn;
    const animlod::ProjectedSphere sphere = animlod::project_sphere(lod_camera, center, asset.sphere_radius);
    // Level per chain.
    for (size_t c = 0; c < asset.chains.size(); ++c) {
      const ChainSubset& subset = subsets_[static_cast<size_t>(placement.asset)][c];
      const Chain& chain = asset.chains[c];
      int selected = 0;  // index into the MSFT_lod chain
      if (subset.forced < 0 && chain.selection_count > 1 && chain.has_errors)
        selected = character.selectors[c].select_by_error(subset.errors.data(), subset.errors.size(), sphere.distance, focal);
      else if (subset.forced < 0 && chain.selection_count > 1 && chain.has_coverages)
        selected = character.selectors[c].select_by_coverage(subset.coverages.data(), subset.coverages.size(),
                                                             sphere.coverage);
      character.levels[c] = subset.forced >= 0 ? subset.forced : subset.drawn[static_cast<size_t>(selected)];
    }
    share_motion_levels(asset, character.levels);
    for (size_t c = 0; c < asset.chains.size(); ++c) {
      const Level& chosen = asset.chains[c].levels[static_cast<size_t>(character.levels[c])];
      counts.triangles += static_cast<int64_t>(asset.meshes[static_cast<size_t>(chosen.mesh)].triangle_count());
      ++counts.levels[static_cast<size_t>(std::min(chosen.lod_index(), 15))];
    }
    // Poses due this frame, once per skeleton the chosen levels use.
    const int interval = mode_.frame_skipping ? animlod::animation_update_interval(sphere.coverage, rate) : 1;
    for (size_t c = 0; c < asset.chains.size(); ++c) {
      const int rig = asset.chains[c].levels[static_cast<size_t>(character.levels[c])].rig;
      bool seen = false;
      for (size_t d = 0; d < c; ++d)
        seen = seen || asset.chains[d].levels[static_cast<size_t>(character.levels[d])].rig == rig;
      if (seen) continue;
      PoseCache& cache = cache_for(character, rig);
      const bool due = !cache.valid || !character.was_visible ||
                       animlod::animation_update_due(frame, static_cast<uint32_t>(i), interval);
      if (!due) continue;
      update_pose(asset, placement, rig, time, cache);
      ++counts.updates;
      counts.joints += static_cast<int64_t>(asset.rigs[static_cast<size_t>(rig)].pose_count());
    }
    // Morph weights at the clip time of the pose drawn with them, sampled with it and held with it
    // on skipped frames.
    for (size_t c = 0; c < asset.chains.size(); ++c) {
      const int drawn = character.levels[c];
      const Level& level = asset.chains[c].levels[static_cast<size_t>(drawn)];
      const PoseCache& cache = cache_for(character, level.rig);
      if (!morph_weights_due(cache.posed_frame == frame, character.morph_levels[c], drawn)) continue;
      character.morph_levels[c] = drawn;
      std::vector<float>& weights = character.morph_weights[c];
      weights.resize(level.morph.target_count());
      if (!weights.empty()) level.morph.sample(static_cast<size_t>(placement.clip), cache.clip_time, weights.data());
    }
  }
}

Gathered CrowdAnimator::gather(float* buffer, InstanceGpu* instances) {
  // Count instances per bucket, then place them bucket by bucket.
  std::vector<uint32_t> sizes(all_buckets_.size(), 0);
  const std::vector<Placement>& placements = scene_.placements();
  for (size_t i = 0; i < characters_.size(); ++i) {
    if (!characters_[i].visible) continue;
    const std::vector<int>& base = bucket_base_[static_cast<size_t>(placements[i].asset)];
    for (size_t c = 0; c < characters_[i].levels.size(); ++c)
      ++sizes[static_cast<size_t>(base[c] + characters_[i].levels[c])];
  }
  std::vector<uint32_t> next(all_buckets_.size(), 0);
  buckets_.clear();
  uint32_t total = 0;
  for (size_t b = 0; b < all_buckets_.size(); ++b) {
    next[b] = total;
    if (sizes[b] == 0) continue;
    Bucket bucket = all_buckets_[b];
    bucket.first = total;
    bucket.count = sizes[b];
    buckets_.push_back(bucket);
    total += sizes[b];
  }
  Gathered out;
  for (size_t i = 0; i < characters_.size(); ++i) {
    Character& character = characters_[i];
    if (!character.visible) continue;
    const Placement& placement = placements[i];
    const Asset& asset = assets_[static_cast<size_t>(placement.asset)];
    const std::vector<int>& base = bucket_base_[static_cast<size_t>(placement.asset)];
    for (size_t c = 0; c < character.levels.size(); ++c) {
      const int level = character.levels[c];
      const Level& drawn = asset.chains[c].levels[static_cast<size_t>(level)];
      PoseCache& cache = cache_for(character, drawn.rig);
      if (cache.gathered_frame != frame_) {  // upload each skeleton's palette once per frame
        cache.gathered_frame = frame_;
        cache.gathered_base = static_cast<uint32_t>(out.floats / 4);
        std::copy(cache.rows.begin(), cache.rows.end(), buffer + out.floats);
        out.floats += cache.rows.size();
        out.matrices += cache.rows.size() / 12;
      }
      const std::vector<float>& weights = character.morph_weights[c];
      const uint32_t morph_base = weights.empty() ? 0 : static_cast<uint32_t>(out.floats / 4);
      std::copy(weights.begin(), weights.end(), buffer + out.floats);
      std::fill(buffer + out.floats + weights.size(), buffer + out.floats + padded_to_texels(weights.size()), 0.0f);
      out.floats += padded_to_texels(weights.size());
      instances[next[static_cast<size_t>(base[c] + level)]++] = {placement.position.x, placement.position.y, placement.position.z,
                                                                  placement.yaw, cache.gathered_base,
                                                                  static_cast<uint32_t>(drawn.lod_index()), morph_base};
    }
  }
  out.instances = total;
  return out;
}

}  // namespace crowd
