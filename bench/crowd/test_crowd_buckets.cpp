// Level buckets of the crowd for a hand-built scene (no GL, no file): characters at known
// distances in front of the camera get the levels their projected errors allow in each mode,
// and the gathered instances, palettes and morph weights are laid out bucket by bucket.
#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "crowd_animation.hpp"
#include "crowd_scene.hpp"

namespace {

using namespace crowd;

// A character chain as `animlod character` writes it: the MSFT_lod chain (g, m) = (0, 0), (1, 1),
// (2, 2) with errors 0, 0.01, 0.04, then the other cells of the 3 x 3 grid. Mesh level g has
// 4, 2, 1 triangles; motion level m a skeleton of 3, 2, 1 joints.
Asset hand_built_asset() {
  Asset asset;
  for (int triangles : {4, 2, 1}) {
    MeshData mesh;
    for (int t = 0; t < triangles; ++t) mesh.indices.insert(mesh.indices.end(), {0u, 1u, 2u});
    asset.meshes.push_back(mesh);
  }
  for (int joints : {3, 2, 1}) {
    Rig rig;
    rig.skin = static_cast<int>(asset.rigs.size());
    for (int j = 0; j < joints; ++j) {
      rig.parents.push_back(j - 1);
      rig.nodes.push_back(j);
      rig.rest_translations.insert(rig.rest_translations.end(), {0.0f, j ? 0.5f : 0.0f, 0.0f});
      rig.rest_rotations.insert(rig.rest_rotations.end(), {0.0f, 0.0f, 0.0f, 1.0f});
      rig.rest_scales.insert(rig.rest_scales.end(), {1.0f, 1.0f, 1.0f});
      rig.joint_nodes.push_back(j);
      for (int k = 0; k < 16; ++k) rig.inverse_bind.push_back(k % 5 == 0 ? 1.0f : 0.0f);
    }
    rig.root_name = "root";
    asset.rigs.push_back(rig);
    asset.clips.emplace_back();  // a clip without channels: the rest pose
  }
  Chain chain;
  chain.has_errors = true;
  auto add = [&](int g, int m, float error) {
    Level level;
    level.mesh_level = g;
    level.motion_level = m;
    level.error = error;
    level.mesh = g;
    level.rig = m;
    level.clips = {m};
    chain.levels.push_back(level);
  };
  add(0, 0, 0.0f);
  add(1, 1, 0.01f);
  add(2, 2, 0.04f);
  chain.selection_count = 3;
  for (int g = 0; g < 3; ++g)
    for (int m = 0; m < 3; ++m)
      if (g != m) add(g, m, 0.0f);  // grid cells record no error of their own
  asset.chains.push_back(chain);
  asset.clip_names = {"rest"};
  asset.bounds_min = glm::vec3(-0.5f, 0.0f, -0.5f);
  asset.bounds_max = glm::vec3(0.5f, 1.8f, 0.5f);
  asset.sphere_center = glm::vec3(0.0f, 0.9f, 0.0f);
  asset.sphere_radius = 1.0f;
  return asset;
}

// Characters at distances 5, 15, 30 and 100 in front of a camera at the sphere centres' height,
// and one behind it. Focal length 1000 px, budget 1 px: a level of error e fits beyond 1000 e.
struct HandBuiltScene {
  std::vector<Asset> assets = one_asset();
  CrowdOptions options;
  CrowdScene scene;
  Camera camera;
  animlod::LodCamera lod_camera;

  HandBuiltScene() : scene(placements(), 200.0f, 1.8f) {
    options.pixel_error = 1.0f;
    options.hysteresis = 0.0f;
    const float fov = 2.0f * std::atan(0.5f);
    camera = make_camera(glm::vec3(0.0f, 0.9f, 0.0f), glm::vec3(0.0f, 0.9f, -1.0f), fov, 1.0f, 0.1f, 1000.0f);
    lod_camera.position = camera.eye;
    lod_camera.vertical_fov = fov;
    lod_camera.viewport_height = 1000.0f;
  }

  static std::vector<Asset> one_asset() {
    std::vector<Asset> out;
    out.push_back(hand_built_asset());  // move-only (clips point into their own keys)
    return out;
  }

  static std::vector<Placement> placements() {
    std::vector<Placement> out;
    for (float distance : {5.0f, 15.0f, 30.0f, 100.0f, -20.0f}) {
      Placement p;
      p.position = glm::vec3(0.0f, 0.0f, -distance);
      out.push_back(p);
    }
    return out;
  }

  // (mesh level, motion level) -> instances drawn, after one frame of `mode`.
  std::map<std::pair<int, int>, uint32_t> run(const char* name, bool geometry, bool motion, FrameCounts& counts,
                                              std::vector<InstanceGpu>& instances) {
    CrowdAnimator animator(assets, scene, options);
    Mode mode;
    mode.name = name;
    mode.geometry_levels = geometry;
    mode.motion_levels = motion;
    animator.start(mode);
    animator.animate(camera, lod_camera, 0, 0.0f, counts);
    std::vector<float> buffer(animator.max_buffer_floats());
    instances.resize(animator.max_instances());
    const Gathered gathered = animator.gather(buffer.data(), instances.data());
    instances.resize(gathered.instances);
    std::map<std::pair<int, int>, uint32_t> cells;
    uint32_t next = 0;
    const Chain& chain = assets[0].chains[0];
    for (const Bucket& bucket : animator.buckets()) {
      CHECK(bucket.first == next);  // buckets tile the instance array in order
      next += bucket.count;
      const Level& level = chain.levels[static_cast<size_t>(bucket.level)];
      cells[{level.mesh_level, level.motion_level}] = bucket.count;
    }
    CHECK(gathered.floats == 12 * static_cast<size_t>(counts.joints));  // every drawn skeleton uploaded once
    CHECK(gathered.matrices == static_cast<size_t>(counts.joints));
    return cells;
  }
};

}  // namespace

TEST_CASE("crowd buckets: the selected chain level, reduced in geometry, motion or both by the mode") {
  HandBuiltScene s;
  FrameCounts counts;
  std::vector<InstanceGpu> instances;
  using Cells = std::map<std::pair<int, int>, uint32_t>;
  // Selected chain levels: 0 at distance 5, 1 at 15 and 30 (0.04 would show 2.7 and 1.3 px), 2 at 100.
  Cells cells = s.run("G+MLoD", true, true, counts, instances);
  CHECK(counts.drawn == 4);  // the character behind the camera is culled
  CHECK(cells == Cells{{{0, 0}, 1}, {{1, 1}, 2}, {{2, 2}, 1}});
  CHECK(counts.triangles == 4 + 2 + 2 + 1);
  CHECK(counts.joints == 3 + 2 + 2 + 1);
  CHECK(counts.levels[0] == 1);
  CHECK(counts.levels[1] == 2);
  CHECK(counts.levels[2] == 1);

  cells = s.run("GLoD", true, false, counts, instances);
  CHECK(cells == Cells{{{0, 0}, 1}, {{1, 0}, 2}, {{2, 0}, 1}});
  CHECK(counts.triangles == 4 + 2 + 2 + 1);
  CHECK(counts.joints == 4 * 3);

  cells = s.run("MLoD", false, true, counts, instances);
  CHECK(cells == Cells{{{0, 0}, 1}, {{0, 1}, 2}, {{0, 2}, 1}});
  CHECK(counts.triangles == 4 * 4);
  CHECK(counts.joints == 3 + 2 + 2 + 1);

  cells = s.run("Original", false, false, counts, instances);
  CHECK(cells == Cells{{{0, 0}, 4}});
  CHECK(counts.joints == 4 * 3);
  // Each instance points at its own palette (3 joints of 3 texels).
  for (size_t i = 0; i < instances.size(); ++i) CHECK(instances[i].palette_base == 9 * i);
}

TEST_CASE("crowd level colours: the tint and the level histogram follow the level drawn, not the one selected") {
  // Selected chain levels 0, 1, 1, 2 (by distance) in every mode; Original draws level 0 for all
  // of them (its tints and histogram counted the selected levels: no level-0 colour on screen).
  HandBuiltScene s;
  FrameCounts counts;
  std::vector<InstanceGpu> instances;
  auto tints = [&instances]() {
    std::vector<uint32_t> out;
    for (const InstanceGpu& instance : instances) out.push_back(instance.tint);
    return out;
  };
  using Tints = std::vector<uint32_t>;
  s.run("Original", false, false, counts, instances);
  CHECK(tints() == Tints{0, 0, 0, 0});
  CHECK(counts.levels[0] == 4);
  CHECK(counts.levels[1] == 0);
  CHECK(counts.levels[2] == 0);
  s.run("GLoD", true, false, counts, instances);  // mesh levels 0, 1, 1, 2 at motion level 0
  CHECK(tints() == Tints{0, 1, 1, 2});
  CHECK(counts.levels[1] == 2);
  s.run("G+MLoD", true, true, counts, instances);
  CHECK(tints() == Tints{0, 1, 1, 2});
  // A chain of geometry levels only: MLoD has no coarser level to draw and draws level 0.
  for (Level& level : s.assets[0].chains[0].levels) level.motion_level = 0;
  s.run("MLoD", false, true, counts, instances);
  CHECK(tints() == Tints{0, 0, 0, 0});
  CHECK(counts.levels[0] == 4);
}

TEST_CASE("crowd grid: a forced cell is drawn by every character, the nearest coarser-or-equal one if missing") {
  HandBuiltScene s;
  s.assets[0].chains[0].levels.pop_back();  // drop the (2, 1) cell
  CrowdAnimator animator(s.assets, s.scene, s.options);
  const int forced[2] = {2, 1};
  animator.start(Mode(), forced);
  FrameCounts counts;
  animator.animate(s.camera, s.lod_camera, 0, 0.0f, counts);
  CHECK(counts.triangles == 4 * 2);  // (2, 1) missing: (1, 1) is the most reduced within it
  CHECK(counts.joints == 4 * 2);
}

TEST_CASE("crowd frame skipping: far characters keep their pose for several frames") {
  HandBuiltScene s;
  s.options.skip_full_coverage = 0.5f;  // coverage 0.41 at 5 units: every frame; 0.13 to 0.02 beyond: every 3 to 8
  CrowdAnimator animator(s.assets, s.scene, s.options);
  Mode mode;
  mode.frame_skipping = true;
  animator.start(mode);
  FrameCounts counts;
  animator.animate(s.camera, s.lod_camera, 0, 0.0f, counts);
  CHECK(counts.updates == 4);  // the first frame poses every drawn character
  int updates = 0;
  for (uint64_t frame = 1; frame <= 8; ++frame) {
    animator.animate(s.camera, s.lod_camera, frame, static_cast<float>(frame) / 30.0f, counts);
    updates += counts.updates;
  }
  CHECK(updates > 0);
  CHECK(updates >= 8);           // the near character every frame
  CHECK(updates <= 8 + 3 + 2 + 1);  // the others every 3, 7 and 8 frames
}

TEST_CASE("crowd morph weights: each instance gets its level's weights at its clip time, after its palette") {
  // The crowd drew a mesh's default weights only: a clip's weights channel was not played.
  HandBuiltScene s;
  Asset& asset = s.assets[0];
  asset.clips[0].duration = 2.0f;  // a clip of 2 s (no joint channel: the rest pose)
  MorphPlayback& morph = asset.chains[0].levels[0].morph;
  morph.defaults = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  morph.tracks.emplace_back();
  std::string error;
  REQUIRE(MorphWeightsTrack::make({0.0f, 2.0f}, {0, 0, 0, 0, 0, 2, 4, 6, 8, 10}, 5, animlod::Interpolation::linear,
                                  morph.tracks.back(), error));
  std::vector<Placement> placements = HandBuiltScene::placements();
  placements[1].phase = 1.0f;
  const CrowdScene scene(placements, 200.0f, 1.8f);
  CrowdAnimator animator(s.assets, scene, s.options);
  Mode original;
  animator.start(original);
  FrameCounts counts;
  animator.animate(s.camera, s.lod_camera, 15, 0.5f, counts);
  std::vector<float> buffer(animator.max_buffer_floats());
  std::vector<InstanceGpu> instances(animator.max_instances());
  const Gathered gathered = animator.gather(buffer.data(), instances.data());
  REQUIRE(gathered.instances == 4);
  // The instances in placement order, each 3 joints (9 texels) then 5 weights padded to 8 floats.
  for (size_t i = 0; i < 4; ++i) {
    CHECK(instances[i].palette_base == 11 * i);
    CHECK(instances[i].morph_base == 11 * i + 9);
    const float t = i == 1 ? 1.5f : 0.5f;  // seconds into the clip: time 0.5 plus the phase
    const float* weights = buffer.data() + 4 * instances[i].morph_base;
    CHECK(std::vector<float>(weights, weights + 8) == std::vector<float>{t, 2 * t, 3 * t, 4 * t, 5 * t, 0, 0, 0});
  }
  CHECK(gathered.matrices == 12);
  CHECK(gathered.floats == 4 * (36 + 8));
}

TEST_CASE("crowd morph weights: a level drawn on a frame its pose is held plays its own weights") {
  // GLoD draws mesh levels 0 and 1 on one skeleton: the nearest character, stepping back into
  // level 1 on a frame that frame skipping holds its pose on, shows level 1's weights.
  HandBuiltScene s;
  s.options.skip_full_coverage = 0.5f;  // from 15 units on every 3 to 8 frames
  Chain& chain = s.assets[0].chains[0];
  chain.levels[0].morph.defaults = {1.0f};
  chain.levels[static_cast<size_t>(chain.find(1, 0))].morph.defaults = {2.0f};
  CrowdAnimator animator(s.assets, s.scene, s.options);
  Mode mode;
  mode.geometry_levels = true;
  mode.frame_skipping = true;
  animator.start(mode);
  FrameCounts counts;
  std::vector<float> buffer(animator.max_buffer_floats());
  std::vector<InstanceGpu> instances(animator.max_instances());
  // (level tint, morph weight) of the character placed 5 units in front of the camera's start.
  auto nearest = [&]() {
    const Gathered gathered = animator.gather(buffer.data(), instances.data());
    for (size_t i = 0; i < gathered.instances; ++i)
      if (instances[i].z == -5.0f) return std::make_pair(instances[i].tint, buffer[4 * instances[i].morph_base]);
    return std::make_pair(0u, -1.0f);
  };
  animator.animate(s.camera, s.lod_camera, 0, 0.0f, counts);
  CHECK(nearest() == std::make_pair(0u, 1.0f));
  const Camera back = make_camera(s.camera.eye + glm::vec3(0.0f, 0.0f, 10.0f), glm::vec3(0.0f, 0.9f, -1.0f), 2.0f * std::atan(0.5f),
                                  1.0f, 0.1f, 1000.0f);
  animlod::LodCamera lod_back = s.lod_camera;
  lod_back.position = back.eye;
  animator.animate(back, lod_back, 1, 1.0f / 30.0f, counts);
  REQUIRE(counts.updates == 0);  // every pose held (updated every 3, 6, 8 and 8 frames)
  CHECK(nearest() == std::make_pair(1u, 2.0f));
}
