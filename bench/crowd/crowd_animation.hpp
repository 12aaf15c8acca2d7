// The CPU half of the crowd pipeline (motion LoD paper, seeds/000, Section 3 and Fig. 2): per
// frame, cull each character against the view frustum, choose its level per chain with the
// core's LodSelector (hysteresis) among the levels the mode allows, decide with the core's
// frame-skipping rate whether its pose is due, and if so sample its clip and run FK + the skin
// palette (pose.hpp), and the morph weights of levels whose clips animate them at the same clip
// time. The palettes and morph weights of all drawn characters are then gathered into one buffer
// and the instances sorted into one bucket per (chain, level) for instanced drawing.
#pragma once

#include <cstdint>
#include <vector>

#include "animlod/lod_selector.hpp"
#include "crowd_options.hpp"
#include "crowd_scene.hpp"
#include "lod_asset.hpp"

namespace crowd {

// Per-instance data the vertex shader reads (28 bytes). Bases count RGBA32F texels of the
// gathered buffer.
struct InstanceGpu {
  float x, y, z, yaw;     // placement
  uint32_t palette_base;  // first texel of the instance's palette (3 rows a joint)
  uint32_t tint;          // Level::lod_index() of the level drawn, for --level-colors
  uint32_t morph_base;    // first texel of its morph weights (4 a texel; 0 where its mesh has none)
};

// What CrowdAnimator::gather wrote.
struct Gathered {
  size_t floats = 0;     // palette rows and morph weights: the floats of the texture buffer
  size_t matrices = 0;   // palette matrices among them
  size_t instances = 0;
};

// One instanced draw: the instances [first, first + count) of the gathered instance array.
struct Bucket {
  int asset = 0, chain = 0, level = 0;
  uint32_t first = 0, count = 0;
};

struct FrameCounts {
  int drawn = 0;              // characters inside the frustum
  int64_t triangles = 0;      // submitted
  int64_t joints = 0;         // pose nodes evaluated by FK (characters whose pose was due)
  int64_t palette_joints = 0; // matrices uploaded
  int updates = 0;            // (character, skeleton) poses updated
  std::vector<int> levels;    // drawn chain instances per Level::lod_index() of the level drawn
};

class CrowdAnimator {
 public:
  CrowdAnimator(const std::vector<Asset>& assets, const CrowdScene& scene, const CrowdOptions& options);

  // Starts a mode: selectors and pose caches reset. The selector picks a level of each chain's
  // MSFT_lod chain by its error; the mode then draws that level's (mesh level, motion level)
  // with the motion level (GLoD) or the mesh level (MLoD) set to 0, or both (Original), as the
  // paper compares them at the same simplification rate. With `forced` (mesh level, motion
  // level) every chain draws that combination (or the nearest coarser-or-equal one it has).
  void start(const Mode& mode, const int* forced = nullptr);

  // Selects levels and updates due poses for `frame` at animation time `time` (seconds).
  void animate(const Camera& camera, const animlod::LodCamera& lod_camera, uint64_t frame, float time, FrameCounts& counts);

  // Upper bounds of the gathered sizes, for buffer allocation.
  size_t max_buffer_floats() const { return max_buffer_floats_; }
  size_t max_instances() const { return max_instances_; }

  // Writes the drawn characters' palettes (3 x 4 rows per joint, 12 floats), each drawn chain's
  // morph weights where its level plays them (padded to 4 floats) and the instances (sorted by
  // bucket) into `buffer` and `instances`. buckets() then lists the draws.
  Gathered gather(float* buffer, InstanceGpu* instances);
  const std::vector<Bucket>& buckets() const { return buckets_; }

 private:
  struct PoseCache {
    int rig = -1;
    std::vector<float> rows;   // (S, 12) palette rows
    float clip_time = 0.0f;    // seconds into the clip the pose was sampled at
    bool valid = false;
    uint64_t posed_frame = UINT64_MAX;  // the frame the pose was last updated
    uint64_t gathered_frame = UINT64_MAX;
    uint32_t gathered_base = 0;
  };
  struct Character {
    std::vector<animlod::LodSelector> selectors;  // per chain
    std::vector<int> levels;                      // per chain, this frame: the level node drawn
    std::vector<std::vector<float>> morph_weights;  // per chain: its level's played weights (T,), else empty
    std::vector<int> morph_levels;                // per chain: the level morph_weights were sampled for, -1: none
    std::vector<PoseCache> caches;                // per rig used so far
    bool visible = false;
    bool was_visible = false;
  };
  struct ChainSubset {
    std::vector<float> errors, coverages;  // of the MSFT_lod levels
    std::vector<int> drawn;                // level drawn for each MSFT_lod level in this mode
    int forced = -1;                       // the level every character draws (--grid)
  };

  PoseCache& cache_for(Character& character, int rig);
  void update_pose(const Asset& asset, const Placement& placement, int rig, float time, PoseCache& cache);

  const std::vector<Asset>& assets_;
  const CrowdScene& scene_;
  const CrowdOptions& options_;
  Mode mode_;
  std::vector<Character> characters_;
  std::vector<std::vector<ChainSubset>> subsets_;  // [asset][chain]
  std::vector<std::vector<int>> bucket_base_;      // [asset][chain] first bucket id
  std::vector<std::vector<const std::vector<int>*>> rig_clips_;  // [asset][rig] clip per original clip
  std::vector<Bucket> all_buckets_, buckets_;
  size_t max_buffer_floats_ = 0, max_instances_ = 0;
  uint64_t frame_ = 0;
  // Scratch for one pose.
  std::vector<float> translations_, rotations_, scales_, world_, palette_;
};

}  // namespace crowd
