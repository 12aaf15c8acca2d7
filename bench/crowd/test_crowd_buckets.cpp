// Level buckets of the crowd for a hand-built scene (no GL, no file): characters at known
// distances in front of the camera get the levels their projected errors allow in each mode,
// and the gathered instances and palettes are laid out bucket by bucket.
#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <vector>

#include "crowd_animation.hpp"
#include "crowd_scene.hpp"

namespace {

using namespace crowd;

// One chain of four levels: (mesh level, motion level, error) = (0, 0, 0), (1, 0, 0.01),
// (0, 1, 0.02), (1, 1, 0.04); meshes of 4 and 2 triangles; rigs of 3 and 2 joints.
Asset hand_built_asset() {
  Asset asset;
  for (int triangles : {4, 2}) {
    MeshData mesh;
    for (int t = 0; t < triangles; ++t) mesh.indices.insert(mesh.indices.end(), {0u, 1u, 2u});
    asset.meshes.push_back(mesh);
  }
  for (int joints : {3, 2}) {
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
  const float errors[4] = {0.0f, 0.01f, 0.02f, 0.04f};
  for (int l = 0; l < 4; ++l) {
    Level level;
    level.mesh_level = l % 2;
    level.motion_level = l / 2;
    level.error = errors[l];
    level.mesh = l % 2;
    level.rig = l / 2;
    level.clips = {l / 2};
    chain.levels.push_back(level);
  }
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

  // Level index -> instances drawn, after one frame of `mode`.
  std::map<int, uint32_t> run(const char* name, bool geometry, bool motion, FrameCounts& counts,
                              std::vector<InstanceGpu>& instances) {
    CrowdAnimator animator(assets, scene, options);
    Mode mode;
    mode.name = name;
    mode.geometry_levels = geometry;
    mode.motion_levels = motion;
    animator.start(mode);
    animator.animate(camera, lod_camera, 0, 0.0f, counts);
    std::vector<float> palettes(animator.max_palette_floats());
    instances.resize(animator.max_instances());
    size_t floats = 0, count = 0;
    animator.gather(palettes.data(), instances.data(), floats, count);
    instances.resize(count);
    std::map<int, uint32_t> levels;
    uint32_t next = 0;
    for (const Bucket& bucket : animator.buckets()) {
      CHECK(bucket.first == next);  // buckets tile the instance array in order
      next += bucket.count;
      levels[bucket.level] = bucket.count;
      for (uint32_t i = bucket.first; i < bucket.first + bucket.count; ++i) CHECK(instances[i].tint == static_cast<uint32_t>(bucket.level));
    }
    CHECK(floats == 12 * static_cast<size_t>(counts.joints));  // every drawn skeleton uploaded once
    return levels;
  }
};

}  // namespace

TEST_CASE("crowd buckets: each mode picks the levels its projected errors allow") {
  HandBuiltScene s;
  FrameCounts counts;
  std::vector<InstanceGpu> instances;

  auto levels = s.run("G+MLoD", true, true, counts, instances);
  CHECK(counts.drawn == 4);  // the character behind the camera is culled
  CHECK(levels == std::map<int, uint32_t>{{0, 1}, {1, 1}, {2, 1}, {3, 1}});
  CHECK(counts.triangles == 4 + 2 + 4 + 2);
  CHECK(counts.joints == 3 + 3 + 2 + 2);

  levels = s.run("GLoD", true, false, counts, instances);
  CHECK(levels == std::map<int, uint32_t>{{0, 1}, {1, 3}});
  CHECK(counts.triangles == 4 + 3 * 2);

  levels = s.run("MLoD", false, true, counts, instances);
  CHECK(levels == std::map<int, uint32_t>{{0, 2}, {2, 2}});
  CHECK(counts.joints == 3 + 3 + 2 + 2);

  levels = s.run("Original", false, false, counts, instances);
  CHECK(levels == std::map<int, uint32_t>{{0, 4}});
  CHECK(counts.joints == 4 * 3);
  // Each instance points at its own palette.
  for (size_t i = 0; i < instances.size(); ++i) CHECK(instances[i].palette_base == 3 * i);
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
