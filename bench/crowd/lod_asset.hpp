// A LoD GLB read with tinygltf into what the crowd draws and animates: per skinned mesh node a
// chain of levels (MSFT_lod, finest first; extras.animlod gives each level's error, mesh level
// and motion level), each level with its merged mesh, the skin it is posed by (joints and their
// ancestor nodes, rest TRS, inverse bind matrices) and its clips (the original animations for
// motion level 0, the re-fitted ones with extras.animlod {clip, motion_level} otherwise).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "animlod/pose.hpp"
#include "morph_weights.hpp"

namespace crowd {

// Skin influences a vertex holds on the GPU (gl_renderer.cpp: two sets of 4).
constexpr int kMaxInfluences = 8;

// One level's geometry: every triangle primitive of its mesh merged into one indexed mesh.
struct MeshData {
  std::vector<float> positions;   // (V, 3) bind-space positions, default morph weights applied
                                  // unless the GPU plays them (morph_targets > 0)
  std::vector<float> normals;     // (V, 3) (area-weighted face normals where the file has none)
  std::vector<float> colors;      // (V, 3) base colour of the vertex's material
  std::vector<uint16_t> joints;   // (V, K) skin joint slots (each joint once)
  std::vector<float> weights;     // (V, K) normalised to sum 1; a vertex of more than K joints
                                  // keeps its K largest weights (Asset::warnings says so)
  int influences = 4;             // K: 4, or kMaxInfluences where a primitive has JOINTS_1 / WEIGHTS_1
  std::vector<uint32_t> indices;  // (M * 3,)
  // Morph targets the GPU adds at each instance's weights, where a clip animates the level node's
  // weights (Level::morph); 0 otherwise.
  int morph_targets = 0;             // T
  std::vector<float> morph_deltas;   // (V, T, 2, 4): position then normal delta of each target, w 0
  size_t vertex_count() const { return positions.size() / 3; }
  size_t triangle_count() const { return indices.size() / 3; }
};

// A skin posed through its joint nodes and every ancestor of them (non-joint armature nodes
// included, as glTF viewers do), in topological order.
struct Rig {
  int skin = -1;                         // glTF skin index
  std::vector<int32_t> parents;          // (P,) pose-node parents, -1 for roots
  std::vector<int> nodes;                // (P,) glTF node of each pose node
  std::vector<float> rest_translations;  // (P, 3)
  std::vector<float> rest_rotations;     // (P, 4) (x, y, z, w)
  std::vector<float> rest_scales;        // (P, 3)
  std::vector<int32_t> joint_nodes;      // (S,) pose node of each skin joint
  std::vector<float> inverse_bind;       // (S, 16) column-major
  std::string root_name;                 // name of the skin's top joint node
  size_t pose_count() const { return parents.size(); }
  size_t joint_count() const { return joint_nodes.size(); }
};

// One animation restricted to the nodes of a rig; owns its keys (move-only: the channels point
// into the key vectors).
struct Clip {
  Clip() = default;
  Clip(Clip&&) = default;
  Clip& operator=(Clip&&) = default;
  Clip(const Clip&) = delete;
  Clip& operator=(const Clip&) = delete;

  std::vector<int> animations;  // glTF animations played together (usually one)
  float duration = 0.0f;  // seconds, the last key time over its channels and its animations' morph weights
  std::vector<std::vector<float>> times, values;  // per channel
  std::vector<animlod::ClipChannel> channels;     // pointing into times / values
  animlod::ClipView view() const { return {channels.data(), channels.size()}; }
};

struct Level {
  int node = -1;          // glTF node
  float error = 0.0f;     // asset units (extras.animlod.error; 0 for level 0)
  float coverage = 0.0f;  // MSFT_screencoverage value (0 when absent)
  int mesh_level = 0;
  int motion_level = 0;
  int mesh = -1;             // index into Asset::meshes
  int rig = -1;              // index into Asset::rigs
  std::vector<int> clips;    // per original clip k: index into Asset::clips
  // Morph weights played per instance, where a clip animates the node's weights (target_count()
  // equals its mesh's morph_targets; 0: the mesh holds its default weights).
  MorphPlayback morph;

  // Where the level stands along its chain, what --level-colors and the report's level histogram
  // count: the coarser of its mesh and motion levels, which is its MSFT_lod index on every chain
  // animlod writes ((i, i), (i, 0) or (0, i)) and 0 for everything Original draws.
  int lod_index() const { return std::max(mesh_level, motion_level); }
};

// A chain of one skinned mesh node. levels[0, selection_count) are the MSFT_lod chain, finest
// first: the selector picks one of them by its error (or coverage). A character chain from
// `animlod character` has geometry level i with motion level i along it, and every other
// (mesh level, motion level) combination as further level nodes listed by the base node's
// extras.animlod_grid[g][m]; those follow in levels[selection_count, ...) so that the GLoD and
// MLoD modes (and the Fig. 1 grid) can draw them.
struct Chain {
  int node = -1;  // the level-0 mesh node
  std::string name;
  std::vector<Level> levels;
  size_t selection_count = 0;
  bool has_errors = false;     // every chain level records extras.animlod.error
  bool has_coverages = false;  // the node has MSFT_screencoverage
  // The same for the chains of one skeleton: their level-0 skins move a joint node in common (the
  // meshes of one character: a body, the visor or eyes skinned to its head, BrainStem's parts).
  int skeleton = 0;

  // The level drawing (mesh level g, motion level m), or -1.
  int find(int mesh_level, int motion_level) const {
    for (size_t l = 0; l < levels.size(); ++l)
      if (levels[l].mesh_level == mesh_level && levels[l].motion_level == motion_level) return static_cast<int>(l);
    return -1;
  }
};

struct Asset {
  std::string path;
  std::vector<Chain> chains;  // one per skinned mesh node of the default scene
  std::vector<MeshData> meshes;
  std::vector<Rig> rigs;
  std::vector<Clip> clips;
  std::vector<std::string> clip_names;  // original clips (motion level 0) that move the character
  // What is drawn other than a glTF viewer would, once per element, each naming it (animlod_crowd
  // prints them on stderr and lists them in the JSON report).
  std::vector<std::string> warnings;
  // Rest-pose bounds of every chain's level 0, posed and skinned by the core (world space).
  glm::vec3 bounds_min{0.0f}, bounds_max{0.0f};
  glm::vec3 sphere_center{0.0f};  // bounding sphere, slightly enlarged for the motion
  float sphere_radius = 0.0f;
  float height() const { return bounds_max.y - bounds_min.y; }
};

// Reads `path` (.glb or .gltf). On failure returns false with `error` naming the file, the
// element (node, skin, animation, accessor) and the reason.
bool load_asset(const std::string& path, Asset& out, std::string& error);

// The same from the bytes of a .glb (they start with "glTF") or a .gltf; `name` stands for the
// file in error messages. Only embedded data is read (the GLB's BIN chunk, data URIs): a URI
// naming a file is an error. The fuzz harness tests/fuzz/cpp/fuzz_crowd_glb.cpp calls it.
bool load_asset_from_memory(const uint8_t* bytes, size_t size, const std::string& name, Asset& out, std::string& error);

}  // namespace crowd
