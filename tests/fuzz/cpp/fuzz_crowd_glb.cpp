// Fuzz harness: the crowd benchmark's LoD GLB loading (bench/crowd/lod_asset.cpp with Debian's
// tinygltf), then one animation step as the crowd runs it (clip sampling, forward kinematics,
// skinning palette). Built only where the crowd is (tinygltf found; fuzz_crowd_glb.cmake); the
// core library never links tinygltf. Input:
//   u8  flags       bit 0: the rest is a whole .glb or .gltf file as given; else:
//   u32 json        byte length of the JSON chunk (lowered to what is left), then the JSON
//                   chunk, then the BIN chunk: the harness writes the GLB container (header,
//                   chunk headers, padding) around them, so that mutations of the JSON or the
//                   data reach the readers behind the container checks (seeds: real GLBs split)
// Invariants: a failure has a message starting with the file's name; an accepted asset has at
// least one chain, levels whose mesh, rig and clips exist, meshes whose indices and skin joint
// slots are in range, rigs in topological order with joint nodes in range, clips that pass
// validate_clip, and a rest-pose bounding sphere of finite positive radius; sampling each clip
// and posing the rig never fails.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "animlod/pose.hpp"
#include "fuzz_input.hpp"
#include "lod_asset.hpp"

namespace {

void append_u32(std::vector<uint8_t>& out, uint32_t value) {
  const auto* bytes = reinterpret_cast<const uint8_t*>(&value);
  out.insert(out.end(), bytes, bytes + 4);
}

// A GLB 2.0 container around a JSON chunk and a BIN chunk (glTF 2.0, Section 4.4).
std::vector<uint8_t> container(const uint8_t* json, size_t json_size, const uint8_t* bin, size_t bin_size) {
  const size_t json_padded = (json_size + 3) & ~size_t{3}, bin_padded = (bin_size + 3) & ~size_t{3};
  std::vector<uint8_t> out = {'g', 'l', 'T', 'F'};
  append_u32(out, 2);
  append_u32(out, static_cast<uint32_t>(12 + 8 + json_padded + (bin_size ? 8 + bin_padded : 0)));
  append_u32(out, static_cast<uint32_t>(json_padded));
  append_u32(out, 0x4E4F534Au);  // "JSON"
  out.insert(out.end(), json, json + json_size);
  out.resize(out.size() + json_padded - json_size, ' ');
  if (bin_size) {
    append_u32(out, static_cast<uint32_t>(bin_padded));
    append_u32(out, 0x004E4942u);  // "BIN\0"
    out.insert(out.end(), bin, bin + bin_size);
    out.resize(out.size() + bin_padded - bin_size, 0);
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  animlod::fuzz::FuzzInput in(data, size);
  const uint8_t flags = in.take<uint8_t>();
  std::vector<uint8_t> file;
  if (in.flag(flags, 0)) {
    file.assign(data + (size - in.remaining()), data + size);
  } else {
    size_t json_size = in.take<uint32_t>();
    if (json_size > in.remaining()) json_size = in.remaining();
    const uint8_t* json = data + (size - in.remaining());
    file = container(json, json_size, json + json_size, in.remaining() - json_size);
  }
  const std::string name = "fuzz.glb";
  crowd::Asset asset;
  std::string error;
  if (!crowd::load_asset_from_memory(file.data(), file.size(), name, asset, error)) {
    ANIMLOD_FUZZ_REQUIRE(error.size() > name.size() && error.compare(0, name.size() + 2, name + ": ") == 0);
    return 0;
  }
  ANIMLOD_FUZZ_REQUIRE(!asset.chains.empty());
  ANIMLOD_FUZZ_REQUIRE(std::isfinite(asset.sphere_radius) && asset.sphere_radius > 0.0f);
  for (const crowd::MeshData& mesh : asset.meshes) {
    ANIMLOD_FUZZ_REQUIRE(mesh.positions.size() % 3 == 0 && mesh.indices.size() % 3 == 0 && !mesh.indices.empty());
    ANIMLOD_FUZZ_REQUIRE(mesh.normals.size() == mesh.positions.size() && mesh.colors.size() == mesh.positions.size());
    const size_t slots = static_cast<size_t>(mesh.influences) * mesh.vertex_count();
    ANIMLOD_FUZZ_REQUIRE(mesh.joints.size() == slots && mesh.weights.size() == slots);
    for (uint32_t index : mesh.indices) ANIMLOD_FUZZ_REQUIRE(index < mesh.vertex_count());
  }
  for (const crowd::Rig& rig : asset.rigs) {
    ANIMLOD_FUZZ_REQUIRE(animlod::validate_parents(rig.parents.data(), rig.pose_count()).ok);
    ANIMLOD_FUZZ_REQUIRE(rig.nodes.size() == rig.pose_count() && rig.rest_translations.size() == 3 * rig.pose_count() &&
                         rig.rest_rotations.size() == 4 * rig.pose_count() && rig.rest_scales.size() == 3 * rig.pose_count());
    ANIMLOD_FUZZ_REQUIRE(rig.inverse_bind.size() == 16 * rig.joint_count());
    for (int32_t node : rig.joint_nodes) ANIMLOD_FUZZ_REQUIRE(node >= 0 && static_cast<size_t>(node) < rig.pose_count());
  }
  for (const crowd::Chain& chain : asset.chains) {
    ANIMLOD_FUZZ_REQUIRE(!chain.levels.empty() && chain.selection_count >= 1 && chain.selection_count <= chain.levels.size());
    for (const crowd::Level& level : chain.levels) {
      ANIMLOD_FUZZ_REQUIRE(level.mesh >= 0 && static_cast<size_t>(level.mesh) < asset.meshes.size());
      ANIMLOD_FUZZ_REQUIRE(level.rig >= 0 && static_cast<size_t>(level.rig) < asset.rigs.size());
      const crowd::MeshData& mesh = asset.meshes[static_cast<size_t>(level.mesh)];
      const crowd::Rig& rig = asset.rigs[static_cast<size_t>(level.rig)];
      for (size_t i = 0; i < mesh.joints.size(); ++i)
        ANIMLOD_FUZZ_REQUIRE(mesh.weights[i] == 0.0f || mesh.joints[i] < rig.joint_count());
      // One animation step of every clip the level plays, as crowd_animation.cpp does it.
      std::vector<float> world(16 * rig.pose_count()), palette(16 * rig.joint_count());
      for (int c : level.clips) {
        if (c < 0) continue;
        ANIMLOD_FUZZ_REQUIRE(static_cast<size_t>(c) < asset.clips.size());
        const crowd::Clip& clip = asset.clips[static_cast<size_t>(c)];
        ANIMLOD_FUZZ_REQUIRE(animlod::validate_clip(clip.view(), rig.pose_count()).ok);
        for (float time : {0.0f, 0.5f * clip.duration, clip.duration}) {
          std::vector<float> t = rig.rest_translations, r = rig.rest_rotations, s = rig.rest_scales;
          const animlod::LocalPose pose{t.data(), r.data(), s.data(), rig.pose_count()};
          animlod::sample_clip(clip.view(), time, animlod::RotationBlend::nlerp, pose);
          ANIMLOD_FUZZ_REQUIRE(animlod::forward_kinematics(rig.parents.data(), pose, world.data()).ok);
          animlod::skin_palette(world.data(), rig.joint_nodes.data(), rig.inverse_bind.data(), rig.joint_count(),
                                palette.data());
        }
      }
    }
  }
  return 0;
}
