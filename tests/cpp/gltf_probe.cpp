// animlod_gltf_probe FILE.glb
//
// Loads a GLB with tinygltf (Debian's libtinygltf, the loader the crowd benchmark uses) and
// prints a one-line JSON summary: vertex and triangle counts, joint count, per-animation
// channel and key counts, and the sums of positions, inverse bind matrices and skin weights.
// tests/python/test_io_gltf.py compares these numbers with what animlod wrote, so that a GLB
// animlod writes is proven readable by an engine-side loader, not only by pygltflib.
// Exit code 1 with the loader's message when the file does not load.

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace {

// One component of an accessor element as a double; normalised integers map to [0, 1].
double read_component(const unsigned char* at, int component_type, bool normalized) {
  switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
      float value;
      std::memcpy(&value, at, sizeof value);
      return value;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
      return normalized ? at[0] / 255.0 : at[0];
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t value;
      std::memcpy(&value, at, sizeof value);
      return normalized ? value / 65535.0 : value;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      std::uint32_t value;
      std::memcpy(&value, at, sizeof value);
      return value;
    }
    default:
      return 0.0;
  }
}

// Sum of every component of every element of accessor `index` (byte stride honoured); NaN when
// the accessor reaches past its buffer, so that a comparison with the expected sum fails.
double accessor_sum(const tinygltf::Model& model, int index) {
  if (index < 0) return 0.0;
  const tinygltf::Accessor& accessor = model.accessors[index];
  if (accessor.bufferView < 0) return 0.0;
  const tinygltf::BufferView& view = model.bufferViews[accessor.bufferView];
  const std::vector<unsigned char>& buffer = model.buffers[view.buffer].data;
  const int components = tinygltf::GetNumComponentsInType(accessor.type);
  const int component_bytes = tinygltf::GetComponentSizeInBytes(accessor.componentType);
  const int stride = accessor.ByteStride(view);
  const size_t start = view.byteOffset + accessor.byteOffset;
  if (accessor.count == 0) return 0.0;
  if (stride <= 0 || start + (accessor.count - 1) * stride + components * component_bytes > buffer.size()) {
    return std::nan("");
  }
  const unsigned char* base = buffer.data() + start;
  double sum = 0.0;
  for (size_t element = 0; element < accessor.count; ++element) {
    for (int c = 0; c < components; ++c) {
      sum += read_component(base + element * stride + c * component_bytes, accessor.componentType, accessor.normalized);
    }
  }
  return sum;
}

int attribute(const tinygltf::Primitive& primitive, const std::string& name) {
  const auto found = primitive.attributes.find(name);
  return found == primitive.attributes.end() ? -1 : found->second;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s FILE.glb\n", argv[0]);
    return 2;
  }
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string error, warning;
  if (!loader.LoadBinaryFromFile(&model, &error, &warning, argv[1])) {
    std::fprintf(stderr, "tinygltf could not load %s: %s\n", argv[1], error.c_str());
    return 1;
  }

  size_t vertices = 0, triangles = 0, morph_targets = 0;
  double position_sum = 0.0, weight_sum = 0.0;
  for (const tinygltf::Mesh& mesh : model.meshes) {
    for (const tinygltf::Primitive& primitive : mesh.primitives) {
      const int positions = attribute(primitive, "POSITION");
      vertices += positions < 0 ? 0 : model.accessors[positions].count;
      triangles += primitive.indices < 0 ? 0 : model.accessors[primitive.indices].count / 3;
      position_sum += accessor_sum(model, positions);
      weight_sum += accessor_sum(model, attribute(primitive, "WEIGHTS_0")) +
                    accessor_sum(model, attribute(primitive, "WEIGHTS_1"));
      morph_targets += primitive.targets.size();
    }
  }
  size_t joints = 0;
  double inverse_bind_sum = 0.0;
  for (const tinygltf::Skin& skin : model.skins) {
    joints += skin.joints.size();
    inverse_bind_sum += accessor_sum(model, skin.inverseBindMatrices);
  }

  std::printf("{\"vertices\": %zu, \"triangles\": %zu, \"joints\": %zu, \"morph_targets\": %zu, ", vertices,
              triangles, joints, morph_targets);
  std::printf("\"position_sum\": %.9g, \"inverse_bind_sum\": %.9g, \"weight_sum\": %.9g, \"animations\": [",
              position_sum, inverse_bind_sum, weight_sum);
  for (size_t a = 0; a < model.animations.size(); ++a) {
    const tinygltf::Animation& animation = model.animations[a];
    size_t keys = 0;
    for (const tinygltf::AnimationSampler& sampler : animation.samplers) {
      keys = std::max(keys, model.accessors[sampler.input].count);
    }
    std::printf("%s{\"channels\": %zu, \"keys\": %zu}", a ? ", " : "", animation.channels.size(), keys);
  }
  std::printf("]}\n");
  return 0;
}
