// Reads a LoD GLB (the format of /work/shared preamble, "The LoD GLB format": MSFT_lod ids on
// the level-0 node, MSFT_screencoverage and extras.animlod on every level, reduced skeletons and
// re-fitted animations for motion levels) with tinygltf, Debian's shared build.
#include "lod_asset.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <utility>

#define GLM_ENABLE_EXPERIMENTAL
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/matrix_decompose.hpp>
#include <tiny_gltf.h>

#include "animation_pointers.hpp"
#include "animlod/lod_selector.hpp"
#include "animlod/skinning.hpp"

namespace crowd {

namespace {

using tinygltf::Model;
using tinygltf::Value;

// Failure with a message; the loader stops at the first one.
struct LoadError {
  std::string message;
};

[[noreturn]] void fail(const std::string& element, const std::string& reason) { throw LoadError{element + ": " + reason}; }

std::string node_label(const Model& model, int node) {
  const std::string& name = model.nodes[static_cast<size_t>(node)].name;
  return "node " + std::to_string(node) + (name.empty() ? "" : " '" + name + "'");
}

std::string animation_label(const Model& model, int animation) {
  const std::string& name = model.animations[static_cast<size_t>(animation)].name;
  return "animation " + std::to_string(animation) + (name.empty() ? "" : " '" + name + "'");
}

std::string channel_label(const Model& model, int animation, size_t channel) {
  return animation_label(model, animation) + " channel " + std::to_string(channel);
}

size_t component_size(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

// One component as a double; normalised integers map to [0, 1] or [-1, 1] (glTF 3.11).
double read_component(const unsigned char* at, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float v;
      std::memcpy(&v, at, 4);
      return v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? at[0] / 255.0 : at[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const auto v = static_cast<int8_t>(at[0]);
      return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      uint16_t v;
      std::memcpy(&v, at, 2);
      return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      int16_t v;
      std::memcpy(&v, at, 2);
      return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      uint32_t v;
      std::memcpy(&v, at, 4);
      return v;
    }
    case TINYGLTF_COMPONENT_TYPE_INT: {
      int32_t v;
      std::memcpy(&v, at, 4);
      return v;
    }
    default: return 0.0;
  }
}

// Buffer view `index`, checked to exist with its buffer.
const tinygltf::BufferView& buffer_view(const Model& model, int index, const std::string& label) {
  if (index < 0 || static_cast<size_t>(index) >= model.bufferViews.size()) fail(label, "buffer view does not exist");
  const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(index)];
  if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model.buffers.size()) fail(label, "buffer does not exist");
  return view;
}

// The bytes [offset, offset + length) of `view`, checked to lie in the view and the view in its buffer.
const unsigned char* view_bytes(const Model& model, const tinygltf::BufferView& view, size_t offset, size_t length,
                                const std::string& label) {
  const std::vector<unsigned char>& data = model.buffers[static_cast<size_t>(view.buffer)].data;
  if (offset + length > view.byteLength || view.byteOffset + view.byteLength > data.size())
    fail(label, "reaches past its buffer view or buffer (" + std::to_string(view.byteOffset + offset + length) +
                    " bytes needed)");
  return data.data() + view.byteOffset + offset;
}

// Accessor `index` as doubles, `components` per element (checked against its type), sparse
// substitutions applied (Blender writes shape keys so), bounds checked against its buffer views
// and buffers.
std::vector<double> read_accessor(const Model& model, int index, int components, const std::string& element) {
  const std::string label = element + " accessor " + std::to_string(index);
  if (index < 0 || static_cast<size_t>(index) >= model.accessors.size()) fail(element, "accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& accessor = model.accessors[static_cast<size_t>(index)];
  const int per_element = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(accessor.type));
  if (per_element != components)
    fail(label, std::to_string(per_element) + " components per element, expected " + std::to_string(components));
  const size_t size = component_size(accessor.componentType);
  if (size == 0) fail(label, "unknown component type " + std::to_string(accessor.componentType));
  // A count near 2^64 wrapped the sizes below round to small numbers (an out-of-bounds write).
  if (accessor.count > std::numeric_limits<uint32_t>::max())
    fail(label, "count " + std::to_string(accessor.count) + " is more than animlod_crowd reads (2^32 - 1 elements)");
  const size_t element_size = size * static_cast<size_t>(components);
  std::vector<double> out(accessor.count * static_cast<size_t>(components), 0.0);  // no buffer view: zeros (glTF 3.6.2.3)
  auto read_element = [&](const unsigned char* at, size_t e) {
    for (int c = 0; c < components; ++c)
      out[e * static_cast<size_t>(components) + static_cast<size_t>(c)] =
          read_component(at + static_cast<size_t>(c) * size, accessor.componentType, accessor.normalized);
  };
  if (accessor.bufferView >= 0 && accessor.count > 0) {
    const tinygltf::BufferView& view = buffer_view(model, accessor.bufferView, label);
    const size_t stride = view.byteStride ? view.byteStride : element_size;
    const unsigned char* data = view_bytes(model, view, accessor.byteOffset, stride * (accessor.count - 1) + element_size, label);
    for (size_t e = 0; e < accessor.count; ++e) read_element(data + e * stride, e);
  }
  if (accessor.sparse.isSparse) {
    const auto& sparse = accessor.sparse;
    const int index_type = sparse.indices.componentType;
    if (index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      fail(label, "sparse indices of component type " + std::to_string(index_type) + ", expected an unsigned integer type");
    if (sparse.count < 0 || sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0)
      fail(label, "sparse count and byte offsets must be >= 0");
    const size_t count = static_cast<size_t>(sparse.count), index_size = component_size(index_type);
    const unsigned char* indices = view_bytes(model, buffer_view(model, sparse.indices.bufferView, label + " sparse indices"),
                                              static_cast<size_t>(sparse.indices.byteOffset), count * index_size,
                                              label + " sparse indices");
    const unsigned char* values = view_bytes(model, buffer_view(model, sparse.values.bufferView, label + " sparse values"),
                                             static_cast<size_t>(sparse.values.byteOffset), count * element_size,
                                             label + " sparse values");
    for (size_t i = 0; i < count; ++i) {
      const double e = read_component(indices + i * index_size, index_type, false);
      if (e >= static_cast<double>(accessor.count))
        fail(label, "sparse index " + std::to_string(static_cast<long long>(e)) + " outside [0, " +
                        std::to_string(accessor.count) + ")");
      read_element(values + i * element_size, static_cast<size_t>(e));
    }
  }
  return out;
}

std::vector<float> to_floats(const std::vector<double>& values, const std::string& element) {
  std::vector<float> out(values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) fail(element, "non-finite value at component " + std::to_string(i));
    out[i] = static_cast<float>(values[i]);
  }
  return out;
}

// Rest TRS of a node (a matrix is decomposed).
void rest_trs(const tinygltf::Node& node, float* t, float* r, float* s) {
  glm::vec3 translation(0.0f), scale(1.0f);
  glm::quat rotation(1.0f, 0.0f, 0.0f, 0.0f);
  if (node.matrix.size() == 16) {
    glm::mat4 m;
    for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = static_cast<float>(node.matrix[static_cast<size_t>(i)]);
    glm::vec3 skew;
    glm::vec4 perspective;
    glm::decompose(m, scale, rotation, translation, skew, perspective);
  } else {
    if (node.translation.size() == 3)
      translation = glm::vec3(node.translation[0], node.translation[1], node.translation[2]);
    if (node.rotation.size() == 4)
      rotation = glm::quat(static_cast<float>(node.rotation[3]), static_cast<float>(node.rotation[0]),
                           static_cast<float>(node.rotation[1]), static_cast<float>(node.rotation[2]));
    if (node.scale.size() == 3) scale = glm::vec3(node.scale[0], node.scale[1], node.scale[2]);
  }
  const float length = glm::length(rotation);
  if (!(length > 1e-6f)) rotation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  else rotation = rotation / length;
  t[0] = translation.x, t[1] = translation.y, t[2] = translation.z;
  r[0] = rotation.x, r[1] = rotation.y, r[2] = rotation.z, r[3] = rotation.w;
  s[0] = scale.x, s[1] = scale.y, s[2] = scale.z;
}

const Value* object_member(const Value& value, const char* key) {
  if (!value.IsObject() || !value.Has(key)) return nullptr;
  return &value.Get(key);
}

// A JSON value of the file as a message quotes it.
std::string json_text(const Value& value) {
  if (value.IsString()) return "'" + value.Get<std::string>() + "'";
  if (!value.IsNumber()) return "a JSON " + std::string(value.IsArray() ? "array" : value.IsObject() ? "object" : "value");
  std::ostringstream text;
  text << value.GetNumberAsDouble();
  return text.str();
}

// The node a JSON id names, or -1 unless it is a whole number in [0, node count) (4.7 is not node 4).
int node_id(const Model& model, const Value& id) {
  if (!id.IsNumber()) return -1;
  const double value = id.GetNumberAsDouble();
  if (!(value >= 0.0 && value < static_cast<double>(model.nodes.size())) || value != std::floor(value)) return -1;
  return static_cast<int>(value);
}

class Loader {
 public:
  Loader(const Model& model, Asset& asset) : model_(model), asset_(asset) {}

  void run() {
    find_parents();
    const std::vector<int> mesh_nodes = skinned_mesh_nodes();
    if (mesh_nodes.empty())
      fail("scene", "no skinned mesh (a node with a mesh and a skin) in the default scene; the crowd needs a skin");
    find_original_clips(mesh_nodes.front());
    for (int node : mesh_nodes) asset_.chains.push_back(read_chain(node));
    group_skeletons();
    compute_bounds();
  }

 private:
  // Chain::skeleton: chains whose level-0 rigs move a joint node in common, transitively, share
  // the lowest chain index among them.
  void group_skeletons() {
    std::vector<std::set<int>> moved;
    for (const Chain& chain : asset_.chains) {
      const Rig& rig = asset_.rigs[static_cast<size_t>(chain.levels.front().rig)];
      std::set<int> nodes;
      for (int32_t joint : rig.joint_nodes) nodes.insert(rig.nodes[static_cast<size_t>(joint)]);
      moved.push_back(std::move(nodes));
    }
    for (size_t c = 0; c < asset_.chains.size(); ++c) asset_.chains[c].skeleton = static_cast<int>(c);
    for (size_t c = 0; c < asset_.chains.size(); ++c)
      for (size_t d = 0; d < c; ++d) {
        const bool shared = std::any_of(moved[c].begin(), moved[c].end(), [&](int n) { return moved[d].count(n) > 0; });
        const int from = asset_.chains[c].skeleton, to = asset_.chains[d].skeleton;
        if (!shared || from == to) continue;
        for (Chain& chain : asset_.chains)
          if (chain.skeleton == std::max(from, to)) chain.skeleton = std::min(from, to);
      }
  }

  // A joint node's name; unnamed: "node<i>", the name animlod gives an unnamed joint
  // (gltf_skin.py), which a character chain's reduced skeletons carry: their roots then match.
  std::string joint_name(int node) const {
    const std::string& name = model_.nodes[static_cast<size_t>(node)].name;
    return name.empty() ? "node" + std::to_string(node) : name;
  }

  void find_parents() {
    parents_.assign(model_.nodes.size(), -1);
    for (size_t n = 0; n < model_.nodes.size(); ++n)
      for (int child : model_.nodes[n].children) {
        if (child < 0 || static_cast<size_t>(child) >= model_.nodes.size())
          fail(node_label(model_, static_cast<int>(n)), "child " + std::to_string(child) + " does not exist");
        if (parents_[static_cast<size_t>(child)] < 0) parents_[static_cast<size_t>(child)] = static_cast<int>(n);
      }
  }

  std::vector<int> ancestors(int node) const {
    std::vector<int> out;
    for (int p = parents_[static_cast<size_t>(node)]; p >= 0 && out.size() <= model_.nodes.size();
         p = parents_[static_cast<size_t>(p)])
      out.push_back(p);
    if (out.size() > model_.nodes.size()) fail(node_label(model_, node), "its ancestors form a cycle");
    return out;
  }

  // Mesh nodes with a skin reachable from the default scene (without scenes, from every root
  // node but the lower levels of a chain, which are roots too).
  std::vector<int> skinned_mesh_nodes() const {
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      const size_t scene = model_.defaultScene >= 0 ? static_cast<size_t>(model_.defaultScene) : 0;
      if (scene >= model_.scenes.size()) fail("scene", "default scene " + std::to_string(scene) + " does not exist");
      roots = model_.scenes[scene].nodes;
    } else {
      const std::set<int> levels = lower_level_nodes();
      for (size_t n = 0; n < model_.nodes.size(); ++n)
        if (parents_[n] < 0 && !levels.count(static_cast<int>(n))) roots.push_back(static_cast<int>(n));
    }
    std::vector<int> out;
    std::set<int> seen;
    std::function<void(int)> visit = [&](int node) {
      if (node < 0 || static_cast<size_t>(node) >= model_.nodes.size()) fail("scene", "node " + std::to_string(node) + " does not exist");
      if (!seen.insert(node).second) return;
      const tinygltf::Node& n = model_.nodes[static_cast<size_t>(node)];
      if (n.mesh >= 0 && n.skin >= 0) out.push_back(node);
      for (int child : n.children) visit(child);
    };
    for (int root : roots) visit(root);
    return out;
  }

  // Nodes that another node lists as its levels: MSFT_lod ids and extras.animlod_grid cells
  // (whose first is the base itself).
  std::set<int> lower_level_nodes() const {
    std::set<int> out;
    for (size_t n = 0; n < model_.nodes.size(); ++n) {
      auto add_levels = [&](const Value* list) {
        for (size_t i = 0; list && list->IsArray() && i < list->ArrayLen(); ++i) {
          const Value& id = list->Get(static_cast<int>(i));
          const int level = node_id(model_, id);
          if (level >= 0 && level != static_cast<int>(n)) out.insert(level);
        }
      };
      const tinygltf::Node& node = model_.nodes[n];
      const auto lod = node.extensions.find("MSFT_lod");
      if (lod != node.extensions.end()) add_levels(object_member(lod->second, "ids"));
      const Value* grid = object_member(node.extras, "animlod_grid");
      for (size_t g = 0; grid && grid->IsArray() && g < grid->ArrayLen(); ++g)
        add_levels(&grid->Get(static_cast<int>(g)));
    }
    return out;
  }

  // extras.animlod of a node or animation, or null.
  static const Value* animlod_extras(const Value& extras) { return object_member(extras, "animlod"); }

  static int motion_level_of_animation(const tinygltf::Animation& animation) {
    const Value* extras = animlod_extras(animation.extras);
    const Value* level = extras ? object_member(*extras, "motion_level") : nullptr;
    return level && level->IsNumber() ? level->GetNumberAsInt() : 0;
  }

  // The original clips: animations of motion level 0 that move the first chain's skin. Exporters
  // such as COLLADA2GLTF write one clip as one unnamed animation per node; unnamed animations
  // that move disjoint nodes are played together, as viewers do, as one clip.
  void find_original_clips(int first_node) {
    const int rig = rig_for_skin(model_.nodes[static_cast<size_t>(first_node)].skin);
    std::vector<int> moving;
    for (size_t a = 0; a < model_.animations.size(); ++a) {
      if (motion_level_of_animation(model_.animations[a]) != 0) continue;
      if (asset_.clips[static_cast<size_t>(clip_for(rig, {static_cast<int>(a)}))].channels.empty()) continue;
      moving.push_back(static_cast<int>(a));
    }
    if (moving.empty())
      fail(node_label(model_, first_node), "no animation moves its skeleton (the crowd needs a clip to play)");
    bool split_clip = moving.size() > 1;
    std::set<int> targets;
    for (int a : moving) {
      const tinygltf::Animation& animation = model_.animations[static_cast<size_t>(a)];
      split_clip = split_clip && animation.name.empty();
      std::set<int> mine;
      for (const tinygltf::AnimationChannel& channel : animation.channels)
        if (channel.target_node >= 0) mine.insert(channel.target_node);  // -1: a pointer at no node
      for (int node : mine) split_clip = split_clip && targets.insert(node).second;
    }
    if (split_clip) {
      original_clips_.push_back(moving);
      asset_.clip_names.push_back(std::to_string(moving.size()) + " per-node animations played together");
      return;
    }
    for (int a : moving) {
      original_clips_.push_back({a});
      const std::string& name = model_.animations[static_cast<size_t>(a)].name;
      asset_.clip_names.push_back(name.empty() ? "animation " + std::to_string(a) : name);
    }
  }

  Chain read_chain(int node) {
    const tinygltf::Node& base = model_.nodes[static_cast<size_t>(node)];
    Chain chain;
    chain.node = node;
    chain.name = base.name.empty() ? "node " + std::to_string(node) : base.name;
    std::vector<int> level_nodes = {node};
    const auto lod = base.extensions.find("MSFT_lod");
    if (lod != base.extensions.end()) {
      const Value* ids = object_member(lod->second, "ids");
      if (!ids || !ids->IsArray()) fail(node_label(model_, node), "MSFT_lod has no 'ids' array");
      for (size_t i = 0; i < ids->ArrayLen(); ++i) {
        const Value& id = ids->Get(static_cast<int>(i));
        const std::string which = "MSFT_lod id " + std::to_string(i) + " (" + json_text(id) + ")";
        const int level_node = node_id(model_, id);
        const std::string base_label = node_label(model_, node);
        if (level_node < 0)
          fail(base_label, which + " is not a node: ids are node indices below " + std::to_string(model_.nodes.size()));
        if (level_node == node) fail(base_label, which + " is the node itself: its ids list the lower levels, other nodes");
        if (std::find(level_nodes.begin(), level_nodes.end(), level_node) != level_nodes.end())
          fail(base_label, which + " repeats an earlier id: each level is a different node");
        level_nodes.push_back(level_node);
      }
    }
    std::vector<float> coverages;
    if (const Value* list = object_member(base.extras, "MSFT_screencoverage")) {
      for (size_t i = 0; list->IsArray() && i < list->ArrayLen(); ++i) {
        const Value& value = list->Get(static_cast<int>(i));
        if (!value.IsNumber())
          fail(node_label(model_, node),
               "MSFT_screencoverage value " + std::to_string(i) + " (" + json_text(value) + ") is not a number");
        coverages.push_back(static_cast<float>(value.GetNumberAsDouble()));
      }
      if (coverages.size() != level_nodes.size())
        fail(node_label(model_, node), "MSFT_screencoverage has " + std::to_string(coverages.size()) + " values for " +
                                           std::to_string(level_nodes.size()) + " levels");
      // The selector's level_for_coverage relies on it (asserted in debug builds only).
      const animlod::Status status = animlod::validate_screen_coverages(coverages.data(), coverages.size());
      if (!status) fail(node_label(model_, node) + " MSFT_screencoverage", status.message);
      chain.has_coverages = true;
    }
    chain.has_errors = true;
    for (size_t i = 0; i < level_nodes.size(); ++i) {
      const int finest_rig = i == 0 ? -1 : chain.levels[0].rig;
      chain.levels.push_back(read_level(level_nodes[i], "level " + std::to_string(i), static_cast<int>(i), 0, finest_rig));
      Level& level = chain.levels.back();
      if (chain.has_coverages) level.coverage = coverages[i];
      const Value* extras = animlod_extras(model_.nodes[static_cast<size_t>(level.node)].extras);
      if (i > 0 && !(extras && object_member(*extras, "error"))) chain.has_errors = false;
    }
    chain.selection_count = chain.levels.size();
    // The rest of a character chain's grid: extras.animlod_grid[g][m] = node of (g, m).
    if (const Value* grid = object_member(base.extras, "animlod_grid")) {
      for (size_t g = 0; grid->IsArray() && g < grid->ArrayLen(); ++g) {
        const Value& row = grid->Get(static_cast<int>(g));
        for (size_t m = 0; row.IsArray() && m < row.ArrayLen(); ++m) {
          const Value& id = row.Get(static_cast<int>(m));
          const int cell = node_id(model_, id);
          const std::string label = "animlod_grid[" + std::to_string(g) + "][" + std::to_string(m) + "]";
          if (cell < 0) fail(node_label(model_, node), label + " (" + json_text(id) + ") is not a node");
          bool listed = false;
          for (const Level& level : chain.levels) listed = listed || level.node == cell;
          if (listed) continue;
          chain.levels.push_back(read_level(cell, label, static_cast<int>(g), static_cast<int>(m), chain.levels[0].rig));
          chain.levels.back().mesh_level = static_cast<int>(g);  // the grid's place wins over extras
          chain.levels.back().motion_level = static_cast<int>(m);
        }
      }
    }
    // A level's skeleton root is level 0's, or an ancestor of it where level 0 is a part skinned
    // to some of the body's joints (a helmet on the head plays the body's reduced skeletons).
    const Rig& finest = asset_.rigs[static_cast<size_t>(chain.levels[0].rig)];
    std::set<std::string> roots{finest.root_name};
    for (int32_t joint : finest.joint_nodes) {
      const int top = finest.nodes[static_cast<size_t>(joint)];
      if (joint_name(top) != finest.root_name) continue;
      for (int ancestor : ancestors(top)) roots.insert(joint_name(ancestor));
      break;
    }
    for (size_t i = 1; i < chain.levels.size(); ++i) {
      const std::string& other = asset_.rigs[static_cast<size_t>(chain.levels[i].rig)].root_name;
      if (!roots.count(other))
        fail(node_label(model_, node), "level node " + std::to_string(i) + " (" + node_label(model_, chain.levels[i].node) +
                                           ") has skeleton root '" + other + "', level 0 has '" + finest.root_name +
                                           "': the levels of a chain must share a skeleton root (or hang below it)");
    }
    return chain;
  }

  // A level node; (mesh_level, motion_level) hold where its extras.animlod does not say.
  // `finest_rig`: the rig of the chain's level 0 (-1 when reading level 0 itself).
  Level read_level(int node, const std::string& name, int mesh_level, int motion_level, int finest_rig) {
    const tinygltf::Node& n = model_.nodes[static_cast<size_t>(node)];
    const std::string label = name + " (" + node_label(model_, node) + ")";
    if (n.mesh < 0 || static_cast<size_t>(n.mesh) >= model_.meshes.size()) fail(label, "has no mesh");
    if (n.skin < 0 || static_cast<size_t>(n.skin) >= model_.skins.size()) fail(label, "has no skin");
    Level level;
    level.node = node;
    level.mesh_level = mesh_level;
    level.motion_level = motion_level;
    if (const Value* extras = animlod_extras(n.extras)) {
      auto number = [&](const char* key, double fallback) {
        const Value* v = object_member(*extras, key);
        return v && v->IsNumber() ? v->GetNumberAsDouble() : fallback;
      };
      level.error = static_cast<float>(number("error", 0.0));
      level.mesh_level = static_cast<int>(number("mesh_level", level.mesh_level));
      level.motion_level = static_cast<int>(number("motion_level", level.motion_level));
      if (!std::isfinite(level.error) || level.error < 0.0f) fail(label, "extras.animlod.error must be a number >= 0");
    }
    level.rig = rig_for_skin(n.skin);
    std::vector<ChannelRef> morph_channels;  // per original clip, the channel of the node's weights
    bool morph_played = false;
    for (size_t k = 0; k < original_clips_.size(); ++k) {
      std::vector<int> animations;
      for (int original : original_clips_[k])
        animations.push_back(animation_for(level, original, finest_rig, label, k));
      level.clips.push_back(clip_for(level.rig, animations));
      morph_channels.push_back(weights_channel(node, animations));
      morph_played = morph_played || morph_channels.back().animation >= 0;
    }
    level.mesh = static_cast<int>(asset_.meshes.size());
    asset_.meshes.push_back(
        read_mesh(n.mesh, n.weights, asset_.rigs[static_cast<size_t>(level.rig)].joint_count(), label, morph_played));
    const size_t targets = static_cast<size_t>(asset_.meshes.back().morph_targets);
    if (targets > 0) level.morph = read_morph_playback(n, targets, morph_channels, label);
    return level;
  }

  // An animation channel by index, or none (animation -1).
  struct ChannelRef {
    int animation = -1;
    size_t channel = 0;
  };

  // The channel of `animations` that animates the morph weights of `node`, or none.
  ChannelRef weights_channel(int node, const std::vector<int>& animations) const {
    for (int a : animations) {
      const std::vector<tinygltf::AnimationChannel>& channels = model_.animations[static_cast<size_t>(a)].channels;
      for (size_t c = 0; c < channels.size(); ++c)
        if (channels[c].target_node == node && channels[c].target_path == "weights") return {a, c};
    }
    return {};
  }

  // The morph weights level node `n` plays, its mesh of `targets` morph targets on the GPU: per
  // original clip its weights channel (`channels`), or its default weights.
  MorphPlayback read_morph_playback(const tinygltf::Node& n, size_t targets, const std::vector<ChannelRef>& channels,
                                    const std::string& label) {
    MorphPlayback playback;
    const std::vector<double> defaults =
        default_morph_weights(n.weights, model_.meshes[static_cast<size_t>(n.mesh)], targets, label + " mesh " + std::to_string(n.mesh));
    playback.defaults.assign(defaults.begin(), defaults.end());
    for (const ChannelRef& ref : channels) {
      playback.tracks.emplace_back();
      if (ref.animation < 0) continue;
      const SamplerKeys& keys = morph_weight_keys(ref.animation, ref.channel);
      std::string error;
      if (!MorphWeightsTrack::make(keys.times, keys.values, targets, keys.interpolation, playback.tracks.back(), error))
        fail(channel_label(model_, ref.animation, ref.channel), error + " (the morph weights of " + label + ")");
    }
    return playback;
  }

  // The animation playing original clip `original` at the level's motion level.
  int animation_for(const Level& level, int original, int finest_rig, const std::string& label, size_t k) {
    if (level.motion_level == 0) return original;
    for (size_t a = 0; a < model_.animations.size(); ++a) {
      const tinygltf::Animation& animation = model_.animations[a];
      const Value* extras = animlod_extras(animation.extras);
      const Value* clip = extras ? object_member(*extras, "clip") : nullptr;
      if (!clip || !clip->IsNumber() || clip->GetNumberAsInt() != original) continue;
      if (motion_level_of_animation(animation) != level.motion_level) continue;
      if (moves_rig(level.rig, static_cast<int>(a))) return static_cast<int>(a);
    }
    // A clip of another character in the same file moves none of this chain's joints, so the
    // character writes no motion level of it: the level stands still, as level 0 does.
    if (finest_rig >= 0 && !moves_rig(finest_rig, original)) return original;
    fail(label, "motion level " + std::to_string(level.motion_level) + " has no animation for clip '" +
                    asset_.clip_names[k] + "' (" + animation_label(model_, original) +
                    ") targeting its skeleton (expected extras.animlod {clip, motion_level})");
  }

  bool moves_rig(int rig, int animation) const {
    const std::vector<int>& nodes = asset_.rigs[static_cast<size_t>(rig)].nodes;
    for (const tinygltf::AnimationChannel& channel : model_.animations[static_cast<size_t>(animation)].channels)
      if (std::find(nodes.begin(), nodes.end(), channel.target_node) != nodes.end()) return true;
    return false;
  }

  int rig_for_skin(int skin) {
    for (size_t r = 0; r < asset_.rigs.size(); ++r)
      if (asset_.rigs[r].skin == skin) return static_cast<int>(r);
    asset_.rigs.push_back(read_rig(skin));
    return static_cast<int>(asset_.rigs.size()) - 1;
  }

  Rig read_rig(int skin_index) {
    const std::string label = "skin " + std::to_string(skin_index);
    // The clips are read for the first skinned node before its level checks its skin index
    // (tests/fuzz/crashes/crowd_glb).
    if (skin_index < 0 || static_cast<size_t>(skin_index) >= model_.skins.size())
      fail(label, "does not exist (the file has " + std::to_string(model_.skins.size()) + " skins)");
    const tinygltf::Skin& skin = model_.skins[static_cast<size_t>(skin_index)];
    if (skin.joints.empty()) fail(label, "has no joints");
    std::set<int> tree;
    for (size_t slot = 0; slot < skin.joints.size(); ++slot) {
      const int joint = skin.joints[slot];
      if (joint < 0 || static_cast<size_t>(joint) >= model_.nodes.size())
        fail(label, "joint " + std::to_string(slot) + " is node " + std::to_string(joint) + ", which does not exist");
      tree.insert(joint);
      for (int a : ancestors(joint)) tree.insert(a);
    }
    std::vector<std::pair<size_t, int>> order;  // (depth, node): parents before children
    for (int node : tree) order.emplace_back(ancestors(node).size(), node);
    std::sort(order.begin(), order.end());
    Rig rig;
    rig.skin = skin_index;
    std::map<int, int> pose_of;
    for (const auto& entry : order) {
      const int node = entry.second;
      pose_of[node] = static_cast<int>(rig.nodes.size());
      rig.nodes.push_back(node);
      const int parent = parents_[static_cast<size_t>(node)];
      rig.parents.push_back(parent >= 0 && pose_of.count(parent) ? pose_of[parent] : -1);
      float t[3], r[4], s[3];
      rest_trs(model_.nodes[static_cast<size_t>(node)], t, r, s);
      rig.rest_translations.insert(rig.rest_translations.end(), t, t + 3);
      rig.rest_rotations.insert(rig.rest_rotations.end(), r, r + 4);
      rig.rest_scales.insert(rig.rest_scales.end(), s, s + 3);
    }
    const std::set<int> joints(skin.joints.begin(), skin.joints.end());
    for (int joint : skin.joints) {
      rig.joint_nodes.push_back(pose_of[joint]);
      if (rig.root_name.empty()) {
        bool top = true;
        for (int a : ancestors(joint)) top = top && !joints.count(a);
        if (top) {
          rig.root_name = joint_name(joint);
        }
      }
    }
    const size_t count = skin.joints.size();
    if (skin.inverseBindMatrices >= 0) {
      rig.inverse_bind = to_floats(read_accessor(model_, skin.inverseBindMatrices, 16, label + " inverseBindMatrices"),
                                   label + " inverseBindMatrices");
      if (rig.inverse_bind.size() < 16 * count)
        fail(label, "inverseBindMatrices holds " + std::to_string(rig.inverse_bind.size() / 16) + " matrices for " +
                        std::to_string(count) + " joints");
      rig.inverse_bind.resize(16 * count);
    } else {
      for (size_t j = 0; j < count; ++j) {
        const glm::mat4 identity(1.0f);
        rig.inverse_bind.insert(rig.inverse_bind.end(), glm::value_ptr(identity), glm::value_ptr(identity) + 16);
      }
    }
    return rig;
  }

  int clip_for(int rig_index, const std::vector<int>& animations) {
    for (size_t c = 0; c < asset_.clips.size(); ++c)
      if (asset_.clips[c].animations == animations && clip_rigs_[c] == rig_index) return static_cast<int>(c);
    asset_.clips.push_back(read_clip(rig_index, animations));
    clip_rigs_.push_back(rig_index);
    return static_cast<int>(asset_.clips.size()) - 1;
  }

  // The keys of a channel's sampler: its interpolation, key times (N,) and outputs, `width`
  // numbers an element (glTF stores a weights channel's T weights a key as T scalars).
  struct SamplerKeys {
    animlod::Interpolation interpolation = animlod::Interpolation::linear;
    std::vector<float> times, values;
  };
  SamplerKeys read_sampler(const tinygltf::Animation& animation, const tinygltf::AnimationChannel& channel, int width,
                           const std::string& element) const {
    if (channel.sampler < 0 || static_cast<size_t>(channel.sampler) >= animation.samplers.size())
      fail(element, "sampler " + std::to_string(channel.sampler) + " does not exist");
    const tinygltf::AnimationSampler& sampler = animation.samplers[static_cast<size_t>(channel.sampler)];
    SamplerKeys keys;
    if (sampler.interpolation.empty() || sampler.interpolation == "LINEAR") keys.interpolation = animlod::Interpolation::linear;
    else if (sampler.interpolation == "STEP") keys.interpolation = animlod::Interpolation::step;
    else if (sampler.interpolation == "CUBICSPLINE") keys.interpolation = animlod::Interpolation::cubic_spline;
    else fail(element, "unknown interpolation '" + sampler.interpolation + "'");
    keys.times = to_floats(read_accessor(model_, sampler.input, 1, element + " input"), element + " input");
    keys.values = to_floats(read_accessor(model_, sampler.output, width, element + " output"), element + " output");
    return keys;
  }

  // The keys of a morph weights channel, read once for both of their uses: the duration of each
  // clip that plays the channel (read_clip) and the tracks of the level node it animates
  // (read_morph_playback).
  const SamplerKeys& morph_weight_keys(int animation_index, size_t channel) {
    const std::pair<int, size_t> ref(animation_index, channel);
    auto found = morph_weight_keys_.find(ref);
    if (found == morph_weight_keys_.end()) {
      const tinygltf::Animation& animation = model_.animations[static_cast<size_t>(animation_index)];
      SamplerKeys keys = read_sampler(animation, animation.channels[channel], 1, channel_label(model_, animation_index, channel));
      found = morph_weight_keys_.emplace(ref, std::move(keys)).first;
    }
    return found->second;
  }

  // Whether `channel` sets the morph weights of a mesh that skin `skin` deforms: the crowd plays it
  // on the level node (Level::morph), and the clip lasts until its last key.
  bool morphs_skinned_mesh(const tinygltf::AnimationChannel& channel, int skin) const {
    if (channel.target_path != "weights" || channel.target_node < 0 || static_cast<size_t>(channel.target_node) >= model_.nodes.size())
      return false;
    const tinygltf::Node& node = model_.nodes[static_cast<size_t>(channel.target_node)];
    return node.mesh >= 0 && node.skin == skin;
  }

  // The channels of `animations` (one clip, or one split into per-node animations) that move the rig.
  Clip read_clip(int rig_index, const std::vector<int>& animations) {
    const Rig& rig = asset_.rigs[static_cast<size_t>(rig_index)];
    std::map<int, int> pose_of;
    for (size_t p = 0; p < rig.nodes.size(); ++p) pose_of[rig.nodes[p]] = static_cast<int>(p);
    Clip clip;
    clip.animations = animations;
    std::vector<animlod::ClipChannel> channels;
    for (int animation_index : animations) {
      const tinygltf::Animation& animation = model_.animations[static_cast<size_t>(animation_index)];
      for (size_t c = 0; c < animation.channels.size(); ++c) {
        const tinygltf::AnimationChannel& channel = animation.channels[c];
        const std::string element = channel_label(model_, animation_index, c);
        if (morphs_skinned_mesh(channel, rig.skin)) {
          const std::vector<float>& times = morph_weight_keys(animation_index, c).times;
          if (!times.empty()) clip.duration = std::max(clip.duration, times.back());
          continue;
        }
        const auto target = pose_of.find(channel.target_node);
        if (target == pose_of.end()) continue;
        animlod::ClipChannel out;
        if (channel.target_path == "translation") out.path = animlod::ChannelPath::translation;
        else if (channel.target_path == "rotation") out.path = animlod::ChannelPath::rotation;
        else if (channel.target_path == "scale") out.path = animlod::ChannelPath::scale;
        else continue;  // a joint's own morph weights (a mesh on a joint node): not drawn by the crowd
        const int width = out.path == animlod::ChannelPath::rotation ? 4 : 3;
        SamplerKeys keys = read_sampler(animation, channel, width, element);
        out.track.interpolation = keys.interpolation;
        clip.times.push_back(std::move(keys.times));
        clip.values.push_back(std::move(keys.values));
        const size_t count = clip.times.back().size();
        const size_t per_key = out.track.interpolation == animlod::Interpolation::cubic_spline ? 3 : 1;
        if (clip.values.back().size() != count * per_key * static_cast<size_t>(width))
          fail(element, "output holds " + std::to_string(clip.values.back().size()) + " numbers for " + std::to_string(count) +
                            " keys");
        out.track.key_count = count;
        out.track.component_count = static_cast<size_t>(width);
        out.track.times = clip.times.back().data();  // re-pointed below once every channel is read
        out.track.values = clip.values.back().data();
        const animlod::Status status = animlod::validate_track(out.track, out.path == animlod::ChannelPath::rotation);
        if (!status) fail(element, status.message);
        out.joint = target->second;
        channels.push_back(out);
        if (count > 0) clip.duration = std::max(clip.duration, clip.times.back().back());
      }
    }
    for (size_t c = 0; c < channels.size(); ++c) {
      channels[c].track.times = clip.times[c].data();
      channels[c].track.values = clip.values[c].data();
    }
    clip.channels = std::move(channels);
    const animlod::Status status = animlod::validate_clip(clip.view(), rig.pose_count());
    if (!status) fail(animation_label(model_, animations.front()) + (animations.size() > 1 ? " and the others played with it" : ""),
                      status.message);
    return clip;
  }

  // Triangles; points and lines are not drawn.
  static bool drawn(const tinygltf::Primitive& primitive) { return primitive.mode < 0 || primitive.mode >= TINYGLTF_MODE_TRIANGLES; }

  // A level's mesh; `node_weights` are the level node's morph weights (empty: its mesh's).
  // `play_morph`: a clip animates the node's weights, so the morph targets go to the GPU
  // (MeshData::morph_targets) and the positions stay without the default weights.
  MeshData read_mesh(int mesh_index, const std::vector<double>& node_weights, size_t joint_count, const std::string& level,
                     bool play_morph) {
    const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(mesh_index)];
    const std::string mesh_label = level + " mesh " + std::to_string(mesh_index);
    const size_t targets = morph_target_count(mesh, mesh_label);
    const std::vector<double> default_weights = default_morph_weights(node_weights, mesh, targets, mesh_label);
    size_t slots = 0;  // influences a vertex lists: 4 per JOINTS_n / WEIGHTS_n set, of the primitive with the most
    for (size_t p = 0; p < mesh.primitives.size(); ++p)
      if (drawn(mesh.primitives[p]))
        slots = std::max(slots, 4 * influence_sets(mesh.primitives[p], mesh_label + " primitive " + std::to_string(p)));
    MeshData out;
    out.influences = static_cast<int>(std::min(slots, static_cast<size_t>(kMaxInfluences)));
    out.morph_targets = play_morph ? static_cast<int>(targets) : 0;
    size_t reduced_vertices = 0;
    std::vector<std::string> warnings;  // said once per mesh (several level nodes may draw it), not silently
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& primitive = mesh.primitives[p];
      const std::string label = mesh_label + " primitive " + std::to_string(p);
      if (!drawn(primitive)) continue;
      auto attribute = [&](const std::string& name) {
        const auto found = primitive.attributes.find(name);
        return found == primitive.attributes.end() ? -1 : found->second;
      };
      if (attribute("POSITION") < 0) fail(label, "has no POSITION");
      std::vector<float> positions = to_floats(read_accessor(model_, attribute("POSITION"), 3, label + " POSITION"), label);
      const size_t count = positions.size() / 3, offset = out.vertex_count();
      // (count, slots): each vertex's sets of 4 one after the other, zeros for a set the
      // primitive does not have.
      std::vector<double> joints(slots * count, 0.0), weights(slots * count, 0.0);
      const size_t sets = influence_sets(primitive, label);
      for (size_t set = 0; set < sets; ++set) {
        const std::string suffix = "_" + std::to_string(set);
        const std::vector<double> set_joints = read_accessor(model_, attribute("JOINTS" + suffix), 4, label + " JOINTS" + suffix);
        const std::vector<double> set_weights =
            read_accessor(model_, attribute("WEIGHTS" + suffix), 4, label + " WEIGHTS" + suffix);
        if (set_joints.size() != 4 * count || set_weights.size() != 4 * count)
          fail(label, "JOINTS" + suffix + " / WEIGHTS" + suffix + " do not have one element per vertex");
        for (size_t v = 0; v < count; ++v)
          for (size_t k = 0; k < 4; ++k) {
            joints[slots * v + 4 * set + k] = set_joints[4 * v + k];
            weights[slots * v + 4 * set + k] = set_weights[4 * v + k];
          }
      }
      std::vector<uint32_t> corners;
      if (primitive.indices >= 0) {
        for (double index : read_accessor(model_, primitive.indices, 1, label + " indices")) {
          if (index < 0 || index >= static_cast<double>(count))
            fail(label, "index " + std::to_string(static_cast<long long>(index)) + " outside [0, " + std::to_string(count) + ")");
          corners.push_back(static_cast<uint32_t>(index));
        }
      } else {
        for (size_t v = 0; v < count; ++v) corners.push_back(static_cast<uint32_t>(v));
      }
      const std::vector<uint32_t> triangles = to_triangles(corners, primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode);
      for (uint32_t index : triangles) out.indices.push_back(static_cast<uint32_t>(offset) + index);
      std::vector<float> normals;
      if (attribute("NORMAL") >= 0) {
        normals = to_floats(read_accessor(model_, attribute("NORMAL"), 3, label + " NORMAL"), label);
        if (normals.size() != positions.size()) fail(label, "NORMAL does not have one element per vertex");
      }
      if (play_morph) append_morph_deltas(primitive, count, !normals.empty(), label, out);
      else apply_default_morph(primitive, default_weights, positions, normals, label);
      if (normals.empty()) normals = face_normals(positions, triangles);
      out.positions.insert(out.positions.end(), positions.begin(), positions.end());
      out.normals.insert(out.normals.end(), normals.begin(), normals.end());
      glm::vec3 color(0.8f);
      if (primitive.material >= 0 && static_cast<size_t>(primitive.material) < model_.materials.size()) {
        const std::vector<double>& factor = model_.materials[static_cast<size_t>(primitive.material)].pbrMetallicRoughness.baseColorFactor;
        if (factor.size() >= 3) color = glm::vec3(factor[0], factor[1], factor[2]);
      }
      std::vector<size_t> unweighted;  // vertices without a positive skin weight
      for (size_t v = 0; v < count; ++v) {
        out.colors.insert(out.colors.end(), {color.r, color.g, color.b});
        const SkinRead read = append_skin(&joints[slots * v], &weights[slots * v], slots, joint_count, label, v, out);
        if (read == SkinRead::reduced) ++reduced_vertices;
        if (read == SkinRead::unweighted) unweighted.push_back(v);
      }
      if (!unweighted.empty())
        warnings.push_back(label + ": " + std::to_string(unweighted.size()) + " of " + std::to_string(count) +
                           " vertices (first: " + std::to_string(unweighted.front()) +
                           ") have no positive skin weight; they follow their first listed joint, as three.js and "
                           "Blender do");
    }
    if (out.indices.empty()) fail(mesh_label, "has no triangles");
    if (reduced_vertices > 0)
      warnings.push_back(mesh_label + ": " + std::to_string(reduced_vertices) + " vertices have more than " +
                         std::to_string(kMaxInfluences) + " skin influences; the GPU skinning keeps the " +
                         std::to_string(kMaxInfluences) + " largest weights of each, renormalised");
    if (warned_meshes_.insert(mesh_index).second) asset_.warnings.insert(asset_.warnings.end(), warnings.begin(), warnings.end());
    return out;
  }

  // How many JOINTS_n / WEIGHTS_n pairs a primitive has, numbered from 0 (glTF 3.7.2.1).
  static size_t influence_sets(const tinygltf::Primitive& primitive, const std::string& label) {
    auto has = [&](const std::string& name) { return primitive.attributes.count(name) > 0; };
    size_t sets = 0;
    for (; has("JOINTS_" + std::to_string(sets)) || has("WEIGHTS_" + std::to_string(sets)); ++sets) {
      const std::string n = std::to_string(sets);
      if (!has("JOINTS_" + n) || !has("WEIGHTS_" + n)) fail(label, "has only one of JOINTS_" + n + " / WEIGHTS_" + n);
    }
    if (sets == 0) fail(label, "has no JOINTS_0 / WEIGHTS_0: a skinned mesh needs both");
    size_t named = 0;
    for (const auto& attribute : primitive.attributes)
      named += attribute.first.rfind("JOINTS_", 0) == 0 || attribute.first.rfind("WEIGHTS_", 0) == 0;
    if (named != 2 * sets) fail(label, "numbers its JOINTS_n / WEIGHTS_n sets with a gap (glTF numbers them 0, 1, 2, ...)");
    return sets;
  }

  // How append_skin read a vertex's skin.
  enum class SkinRead {
    whole,       // every positive weight kept
    reduced,     // more joints than the GPU holds: the largest weights kept
    unweighted,  // no positive weight: full weight on the first listed joint
  };

  // Appends the skin of vertex `vertex` of primitive `label`, `slots` (joint, weight) pairs as the
  // file lists them, to `out` as MeshData::influences slots: its positive weights, a joint listed
  // twice once with their sum, normalised. Where more joints remain than the GPU holds, the
  // largest weights are kept (ties by joint) and renormalised, as animlod's simplifier merges
  // skins (cpp/src/skin_merge.hpp). A vertex without a positive weight (glTF forbids it; Blender
  // before 2.90 and Maya2glTF write the vertices no bone deforms so) follows its first listed
  // joint, as three.js, Blender's importer and animlod's reader (gltf_read.py) move it.
  static SkinRead append_skin(const double* joints, const double* weights, size_t slots, size_t joint_count,
                              const std::string& label, size_t vertex, MeshData& out) {
    auto joint_at = [&](size_t k) {
      if (joints[k] < 0 || joints[k] >= static_cast<double>(joint_count))
        fail(label, "vertex " + std::to_string(vertex) + " uses joint slot " + std::to_string(static_cast<long long>(joints[k])) +
                        ", the skin has " + std::to_string(joint_count));
      return joints[k];
    };
    std::vector<std::pair<double, double>> skin;  // (joint, weight)
    for (size_t k = 0; k < slots; ++k) {
      if (!std::isfinite(weights[k])) fail(label, "vertex " + std::to_string(vertex) + " has a non-finite skin weight");
      if (!(weights[k] > 0.0)) continue;
      const double joint = joint_at(k);
      const auto same = std::find_if(skin.begin(), skin.end(), [&](const auto& influence) { return influence.first == joint; });
      if (same != skin.end()) same->second += weights[k];
      else skin.emplace_back(joint, weights[k]);
    }
    const bool unweighted = skin.empty();
    if (unweighted) skin.emplace_back(joint_at(0), 1.0);
    const size_t kept = static_cast<size_t>(out.influences);
    const bool whole = skin.size() <= kept;
    if (!whole) {
      std::sort(skin.begin(), skin.end(), [](const auto& a, const auto& b) {
        return a.second != b.second ? a.second > b.second : a.first < b.first;
      });
      skin.resize(kept);
    }
    double total = 0.0;
    for (const auto& influence : skin) total += influence.second;
    for (size_t k = 0; k < kept; ++k) {
      out.joints.push_back(k < skin.size() ? static_cast<uint16_t>(skin[k].first) : 0);
      out.weights.push_back(k < skin.size() ? static_cast<float>(skin[k].second / total) : 0.0f);
    }
    return unweighted ? SkinRead::unweighted : whole ? SkinRead::whole : SkinRead::reduced;
  }

  // The morph targets of a mesh's drawn primitives: each has as many (glTF 3.7.2.2), or none.
  static size_t morph_target_count(const tinygltf::Mesh& mesh, const std::string& mesh_label) {
    size_t targets = 0;
    for (const tinygltf::Primitive& primitive : mesh.primitives)
      if (drawn(primitive)) targets = std::max(targets, primitive.targets.size());
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      const size_t own = mesh.primitives[p].targets.size();
      if (drawn(mesh.primitives[p]) && own != 0 && own != targets)
        fail(mesh_label + " primitive " + std::to_string(p), "has " + std::to_string(own) + " morph targets, another primitive of its mesh " +
                                                               std::to_string(targets) + " (glTF gives every primitive of a mesh the same targets)");
    }
    return targets;
  }

  // A mesh node's default morph weights (T,): the node's `weights`, else the mesh's, else zeros.
  static std::vector<double> default_morph_weights(const std::vector<double>& node_weights, const tinygltf::Mesh& mesh,
                                                   size_t targets, const std::string& mesh_label) {
    const std::vector<double>& weights = node_weights.empty() ? mesh.weights : node_weights;
    if (targets == 0) return {};
    if (weights.empty()) return std::vector<double>(targets, 0.0);
    if (weights.size() != targets)
      fail(mesh_label, "has " + std::to_string(targets) + " morph targets for " + std::to_string(weights.size()) +
                           " default morph weights (the node's weights, else the mesh's)");
    for (size_t t = 0; t < targets; ++t)
      if (!std::isfinite(weights[t])) fail(mesh_label, "default morph weight " + std::to_string(t) + " is not a finite number");
    return weights;
  }

  // Target `t`'s `name` (POSITION, NORMAL) deltas of a primitive of `count` vertices, (count, 3);
  // empty where the target does not move it.
  std::vector<float> target_deltas(const tinygltf::Primitive& primitive, size_t t, const char* name, size_t count,
                                   const std::string& label) const {
    const auto found = primitive.targets[t].find(name);
    if (found == primitive.targets[t].end()) return {};
    const std::string target = label + " target " + std::to_string(t);
    std::vector<float> deltas = to_floats(read_accessor(model_, found->second, 3, target + " " + name), target);
    if (deltas.size() != 3 * count) fail(target, std::string(name) + " does not have one element per vertex");
    return deltas;
  }

  // Adds a primitive's morph targets at `weights` (its mesh's default weights, checked by
  // default_morph_weights) to its positions and, where the targets move them, its normals
  // (normalised again; `normals` empty: none read), as a viewer shows the mesh.
  void apply_default_morph(const tinygltf::Primitive& primitive, const std::vector<double>& weights,
                           std::vector<float>& positions, std::vector<float>& normals, const std::string& label) const {
    bool normals_moved = false;
    const size_t count = positions.size() / 3;
    for (size_t t = 0; t < primitive.targets.size(); ++t) {
      if (weights[t] == 0.0) continue;
      auto add = [&](const std::vector<float>& deltas, std::vector<float>& values) {
        for (size_t i = 0; i < deltas.size(); ++i) values[i] += static_cast<float>(weights[t] * deltas[i]);
        return !deltas.empty();
      };
      add(target_deltas(primitive, t, "POSITION", count, label), positions);
      if (!normals.empty()) normals_moved = add(target_deltas(primitive, t, "NORMAL", count, label), normals) || normals_moved;
    }
    for (size_t v = 0; normals_moved && v < count; ++v) {
      float* normal = &normals[3 * v];
      const float length = glm::length(glm::vec3(normal[0], normal[1], normal[2]));
      if (length > 0.0f)
        for (int c = 0; c < 3; ++c) normal[c] /= length;
    }
  }

  // Appends a primitive's morph targets, `count` vertices, to out.morph_deltas (a primitive
  // without targets moves nothing); normal deltas only `with_normals` (the file's normals).
  void append_morph_deltas(const tinygltf::Primitive& primitive, size_t count, bool with_normals, const std::string& label,
                           MeshData& out) const {
    const size_t targets = static_cast<size_t>(out.morph_targets);
    std::vector<float> deltas(count * targets * 8, 0.0f);  // (count, T, 2, 4)
    for (size_t t = 0; t < primitive.targets.size(); ++t) {
      const std::vector<float> moved = target_deltas(primitive, t, "POSITION", count, label);
      const std::vector<float> turned = with_normals ? target_deltas(primitive, t, "NORMAL", count, label) : std::vector<float>();
      for (size_t v = 0; v < count; ++v)
        for (size_t c = 0; c < 3; ++c) {
          float* at = &deltas[(v * targets + t) * 8];
          if (!moved.empty()) at[c] = moved[3 * v + c];
          if (!turned.empty()) at[4 + c] = turned[3 * v + c];
        }
    }
    out.morph_deltas.insert(out.morph_deltas.end(), deltas.begin(), deltas.end());
  }

  static std::vector<uint32_t> to_triangles(const std::vector<uint32_t>& corners, int mode) {
    if (mode == TINYGLTF_MODE_TRIANGLES) return std::vector<uint32_t>(corners.begin(), corners.end() - corners.size() % 3);
    std::vector<uint32_t> out;
    for (size_t i = 2; i < corners.size(); ++i) {
      if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        if (i % 2 == 0) out.insert(out.end(), {corners[i - 2], corners[i - 1], corners[i]});
        else out.insert(out.end(), {corners[i - 1], corners[i - 2], corners[i]});
      } else {  // fan
        out.insert(out.end(), {corners[0], corners[i - 1], corners[i]});
      }
    }
    return out;
  }

  static std::vector<float> face_normals(const std::vector<float>& positions, const std::vector<uint32_t>& triangles) {
    std::vector<glm::vec3> sums(positions.size() / 3, glm::vec3(0.0f));
    auto at = [&](uint32_t v) { return glm::vec3(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]); };
    for (size_t f = 0; f + 2 < triangles.size(); f += 3) {
      const glm::vec3 n = glm::cross(at(triangles[f + 1]) - at(triangles[f]), at(triangles[f + 2]) - at(triangles[f]));
      for (int c = 0; c < 3; ++c) sums[triangles[f + static_cast<size_t>(c)]] += n;
    }
    std::vector<float> out;
    for (const glm::vec3& s : sums) {
      const glm::vec3 n = glm::length(s) > 0.0f ? glm::normalize(s) : glm::vec3(0.0f, 1.0f, 0.0f);
      out.insert(out.end(), {n.x, n.y, n.z});
    }
    return out;
  }

  // The bind-space positions (V, 3) of a level's mesh at its default morph weights.
  static std::vector<float> rest_shape(const MeshData& mesh, const MorphPlayback& morph) {
    std::vector<float> positions = mesh.positions;
    const size_t targets = static_cast<size_t>(mesh.morph_targets);
    for (size_t v = 0; v < mesh.vertex_count(); ++v)
      for (size_t t = 0; t < targets; ++t)
        for (size_t c = 0; c < 3; ++c) positions[3 * v + c] += morph.defaults[t] * mesh.morph_deltas[(v * targets + t) * 8 + c];
    return positions;
  }

  // How far the weights a level's clips play move a vertex of its mesh from where it is at no
  // weight (bind space), at most: the farthest at a key, since between keys the weights blend
  // those of the keys and the displacement is linear in them.
  static float morph_reach(const MeshData& mesh, const MorphPlayback& morph) {
    const size_t targets = static_cast<size_t>(mesh.morph_targets);
    float reach = 0.0f;
    for (const std::vector<float>& weights : targets > 0 ? morph.keyed_weights() : std::vector<std::vector<float>>())
      for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        glm::vec3 moved(0.0f);
        for (size_t t = 0; t < targets; ++t) moved += weights[t] * glm::make_vec3(&mesh.morph_deltas[(v * targets + t) * 8]);
        reach = std::max(reach, glm::length(moved));
      }
    return reach;
  }

  // Rest-pose world bounds: level 0 of every chain at its default morph weights, posed by the
  // core (FK + palette) and skinned by bake_lbs. The bounding sphere also holds what the played
  // morph weights move, of every level.
  void compute_bounds() {
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    float reach = 0.0f;
    for (const Chain& chain : asset_.chains) {
      for (const Level& level : chain.levels)
        reach = std::max(reach, morph_reach(asset_.meshes[static_cast<size_t>(level.mesh)], level.morph));
      const Level& level = chain.levels.front();
      const Rig& rig = asset_.rigs[static_cast<size_t>(level.rig)];
      const MeshData& mesh = asset_.meshes[static_cast<size_t>(level.mesh)];
      const std::vector<float> positions = rest_shape(mesh, level.morph);
      std::vector<float> t = rig.rest_translations, r = rig.rest_rotations, s = rig.rest_scales;
      std::vector<float> world(16 * rig.pose_count()), palette(16 * rig.joint_count());
      const animlod::LocalPose pose{t.data(), r.data(), s.data(), rig.pose_count()};
      animlod::Status status = animlod::forward_kinematics(rig.parents.data(), pose, world.data());
      if (!status) fail("skin " + std::to_string(rig.skin), status.message);
      animlod::skin_palette(world.data(), rig.joint_nodes.data(), rig.inverse_bind.data(), rig.joint_count(), palette.data());
      std::vector<int32_t> joints(mesh.joints.begin(), mesh.joints.end());
      std::vector<float> skinned(positions.size());
      animlod::SkinningInput input;
      input.rest_positions = positions.data();
      input.joints = joints.data();
      input.weights = mesh.weights.data();
      input.skin_matrices = palette.data();
      input.vertex_count = mesh.vertex_count();
      input.influence_count = static_cast<size_t>(mesh.influences);
      input.joint_count = rig.joint_count();
      input.frame_count = 1;
      status = animlod::bake_lbs(input, skinned.data());
      if (!status) fail(chain.name, status.message);
      for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        const glm::vec3 p(skinned[3 * v], skinned[3 * v + 1], skinned[3 * v + 2]);
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
      }
    }
    asset_.bounds_min = lo;
    asset_.bounds_max = hi;
    asset_.sphere_center = 0.5f * (lo + hi);
    asset_.sphere_radius = 0.5f * glm::length(hi - lo) * 1.1f + reach;  // room for limbs swinging out
    if (!(asset_.sphere_radius > 0.0f) || !std::isfinite(asset_.sphere_radius))
      fail("scene", "the skinned meshes have no extent in their rest pose");
  }

  const Model& model_;
  Asset& asset_;
  std::vector<int> parents_;
  std::vector<std::vector<int>> original_clips_;  // animations of each original clip
  std::vector<int> clip_rigs_;  // rig of every clip in asset_.clips
  std::map<std::pair<int, size_t>, SamplerKeys> morph_weight_keys_;  // (animation, channel): morph_weight_keys
  std::set<int> warned_meshes_;  // meshes whose warnings were said (several level nodes may draw one)
};

}  // namespace

namespace {

// What tinygltf reported, on one line and prefixed with the file.
bool tinygltf_failure(const std::string& name, std::string& error) {
  if (error.empty()) error = "tinygltf could not load the file";
  while (!error.empty() && (error.back() == '\n' || error.back() == ' ')) error.pop_back();
  for (char& c : error)
    if (c == '\n') c = ' ';
  error = name + ": " + error;
  return false;
}

bool read_model(const Model& model, const std::string& name, Asset& out, std::string& error) {
  out = Asset();
  out.path = name;
  try {
    Loader(model, out).run();
  } catch (const LoadError& failure) {
    error = name + ": " + failure.message;
    return false;
  }
  return true;
}

// Whether `bytes` open like a JSON object (a .gltf), after a byte order mark and white space.
bool opens_like_json(const uint8_t* bytes, size_t size) {
  size_t at = size >= 3 && std::memcmp(bytes, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
  while (at < size && std::isspace(bytes[at])) ++at;
  return at < size && bytes[at] == '{';
}

// tinygltf's model of a GLB (told by its magic, as the Python reader decides) or glTF JSON, its pointer channels resolved first
// (animation_pointers.hpp); external files are looked up in base_dir.
bool parse_model(tinygltf::TinyGLTF& loader, const uint8_t* bytes, size_t size, const std::string& base_dir,
                 Model& model, std::string& error) {
  // Said in our words: the parsers' own (a JSON syntax error at line 1) do not say what the file is not.
  if (size == 0) {
    error = "empty file";
    return false;
  }
  if (!is_glb(bytes, size) && !opens_like_json(bytes, size)) {
    error = "not a glTF character: neither a GLB (it does not start with 'glTF') nor a .gltf JSON document";
    return false;
  }
  const std::vector<uint8_t> resolved = resolve_animation_pointers(bytes, size);
  if (!resolved.empty()) bytes = resolved.data(), size = resolved.size();
  std::string warnings;
  return is_glb(bytes, size) ? loader.LoadBinaryFromMemory(&model, &error, &warnings, bytes, static_cast<unsigned int>(size), base_dir)
                : loader.LoadASCIIFromString(&model, &error, &warnings, reinterpret_cast<const char*>(bytes),
                                             static_cast<unsigned int>(size), base_dir);
}

}  // namespace

bool load_asset(const std::string& path, Asset& out, std::string& error) {
  std::error_code status;
  if (!std::filesystem::is_regular_file(path, status)) {
    error = path + ": " + (std::filesystem::exists(path, status) ? "not a regular file" : "no such file");
    return false;
  }
  std::ifstream file(path, std::ios::binary);
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (!file.good() && !file.eof()) {
    error = path + ": could not be read";
    return false;
  }
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  const std::string base_dir = std::filesystem::path(path).parent_path().string();
  if (!parse_model(loader, bytes.data(), bytes.size(), base_dir, model, error)) return tinygltf_failure(path, error);
  return read_model(model, path, out, error);
}

bool load_asset_from_memory(const uint8_t* bytes, size_t size, const std::string& name, Asset& out, std::string& error) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  // No file system: every external URI is "not found".
  tinygltf::FsCallbacks no_files{};
  no_files.FileExists = [](const std::string&, void*) { return false; };
  no_files.ExpandFilePath = [](const std::string& path, void*) { return path; };
  no_files.ReadWholeFile = [](std::vector<unsigned char>*, std::string* why, const std::string& path, void*) {
    if (why) *why += "external file '" + path + "' not read (embedded data only)";
    return false;
  };
  no_files.WriteWholeFile = [](std::string*, const std::string&, const std::vector<unsigned char>&, void*) { return false; };
  loader.SetFsCallbacks(no_files);
  if (!parse_model(loader, bytes, size, "", model, error)) return tinygltf_failure(name, error);
  return read_model(model, name, out, error);
}

}  // namespace crowd
