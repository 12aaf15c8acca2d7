// Links the installed animlod::core as an engine would and uses each runtime-facing part of it:
// AQEM (simplify_animated, which pulls OpenMesh through the package's link interface), the LoD
// selector, the pose sampler / FK, and bake_lbs. Exits non-zero if any result is wrong.
#include <animlod/aqem.hpp>
#include <animlod/lod_selector.hpp>
#include <animlod/pose.hpp>
#include <animlod/skinning.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>
#include <vector>

namespace {

int failures = 0;

void check(bool ok, const char* what) {
  std::printf("  %-58s %s\n", what, ok ? "ok" : "FAILED");
  failures += ok ? 0 : 1;
}

// An icosahedron subdivided `levels` times onto the unit sphere: a closed, manifold mesh.
void icosphere(int levels, std::vector<float>& positions, std::vector<int32_t>& faces) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  positions = {-1, t, 0, 1, t, 0, -1, -t, 0, 1, -t, 0, 0, -1, t, 0, 1, t,
               0, -1, -t, 0, 1, -t, t, 0, -1, t, 0, 1, -t, 0, -1, -t, 0, 1};
  faces = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
           3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int32_t, int32_t>, int32_t> middle;
    auto midpoint = [&](int32_t a, int32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto found = middle.find(key);
      if (found != middle.end()) return found->second;
      const auto index = static_cast<int32_t>(positions.size() / 3);
      for (int c = 0; c < 3; ++c) positions.push_back(0.5f * (positions[3 * a + c] + positions[3 * b + c]));
      middle[key] = index;
      return index;
    };
    std::vector<int32_t> finer;
    for (size_t f = 0; f < faces.size(); f += 3) {
      const int32_t a = faces[f], b = faces[f + 1], c = faces[f + 2];
      const int32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      finer.insert(finer.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    faces.swap(finer);
  }
  for (size_t v = 0; v < positions.size(); v += 3) {
    const float length = std::sqrt(positions[v] * positions[v] + positions[v + 1] * positions[v + 1] +
                                   positions[v + 2] * positions[v + 2]);
    for (int c = 0; c < 3; ++c) positions[v + c] /= length;
  }
}

void simplify() {
  std::vector<float> rest;
  std::vector<int32_t> faces;
  icosphere(2, rest, faces);  // 162 vertices, 320 faces
  const size_t vertex_count = rest.size() / 3, face_count = faces.size() / 3;
  // Three frames: the sphere stretched more and more along y.
  std::vector<float> frames;
  for (int f = 0; f < 3; ++f)
    for (size_t v = 0; v < vertex_count; ++v)
      frames.insert(frames.end(), {rest[3 * v], rest[3 * v + 1] * (1.0f + 0.5f * f), rest[3 * v + 2]});
  animlod::AnimatedMeshView mesh;
  mesh.frames = frames.data();
  mesh.faces = faces.data();
  mesh.frame_count = 3;
  mesh.vertex_count = vertex_count;
  mesh.face_count = face_count;
  animlod::AqemOptions options;
  options.target_ratios = {0.25};
  animlod::AqemResult result;
  const animlod::Status status = animlod::simplify_animated(mesh, animlod::AqemVertexData{}, options, result);
  bool in_range = status.ok && result.levels.size() == 1;
  if (in_range) {
    const animlod::AqemLevel& level = result.levels[0];
    const auto kept = static_cast<int32_t>(level.kept_vertices.size());
    for (int32_t index : level.faces) in_range = in_range && index >= 0 && index < kept;
    in_range = in_range && level.faces.size() / 3 <= face_count / 4 && level.faces.size() / 3 >= 40 &&
               level.positions.size() == 3 * 3 * level.kept_vertices.size();
    std::printf("  simplify_animated: %zu -> %zu faces, error %.4g\n", face_count, level.faces.size() / 3, level.error);
  } else {
    std::printf("  simplify_animated: %s\n", status.message.c_str());
  }
  check(in_range, "simplify_animated: icosphere to 25% of its faces");
}

void select() {
  const float errors[4] = {0.0f, 0.01f, 0.04f, 0.16f};
  animlod::LodCamera camera;
  camera.vertical_fov = 2.0f * std::atan(0.5f);
  camera.viewport_height = 1000.0f;
  const float focal = animlod::focal_length_pixels(camera);
  animlod::LodSelector selector;
  int changes = 0, last = -1;
  for (int step = 0; step < 50; ++step) {  // jitter +-2 % around the 1 -> 2 threshold at 40 units
    const glm::vec3 where(0.0f, 0.0f, -40.0f * (step % 2 ? 1.02f : 0.98f));
    const animlod::ProjectedSphere sphere = animlod::project_sphere(camera, where, 1.0f);
    const int level = selector.select_by_error(errors, 4, sphere.distance, focal);
    changes += last >= 0 && level != last;
    last = level;
  }
  check(changes == 0 && last == 1, "LodSelector: no flicker at a threshold");
  check(animlod::animation_update_interval(0.05f) > animlod::animation_update_interval(0.5f),
        "animation_update_interval falls with distance");
}

void pose() {
  // A root and a child one unit along x; the clip turns the root 90 degrees about z in 1 s.
  const int32_t parents[2] = {-1, 0};
  float translations[6] = {0, 0, 0, 1, 0, 0};
  float rotations[8] = {0, 0, 0, 1, 0, 0, 0, 1};
  const float times[2] = {0.0f, 1.0f};
  const float keys[8] = {0, 0, 0, 1, 0, 0, std::sin(0.7853982f), std::cos(0.7853982f)};
  animlod::ClipChannel channel;
  channel.track = {times, keys, 2, 4, animlod::Interpolation::linear};
  channel.joint = 0;
  channel.path = animlod::ChannelPath::rotation;
  const animlod::ClipView clip{&channel, 1};
  animlod::LocalPose local{translations, rotations, nullptr, 2};
  float world[32];
  bool ok = animlod::validate_clip(clip, 2).ok;
  animlod::sample_clip(clip, 1.0f, animlod::RotationBlend::slerp, local);
  ok = ok && animlod::forward_kinematics(parents, local, world).ok;
  float palette[16];
  const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const int32_t child[1] = {1};
  animlod::skin_palette(world, child, identity, 1, palette);
  check(ok && std::fabs(palette[12]) < 1e-6f && std::fabs(palette[13] - 1.0f) < 1e-6f,
        "sample_clip + forward_kinematics + skin_palette");
}

void skin() {
  const float rest[3] = {1.0f, 0.0f, 0.0f};
  const int32_t joints[1] = {0};
  const float weights[1] = {1.0f};
  // Column-major translation by (0, 2, 0).
  const float matrix[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 2, 0, 1};
  animlod::SkinningInput input;
  input.rest_positions = rest;
  input.joints = joints;
  input.weights = weights;
  input.skin_matrices = matrix;
  input.vertex_count = input.influence_count = input.joint_count = input.frame_count = 1;
  float out[3] = {};
  const animlod::Status status = animlod::bake_lbs(input, out);
  check(status.ok && std::fabs(out[0] - 1.0f) < 1e-6f && std::fabs(out[1] - 2.0f) < 1e-6f, "bake_lbs");
}

}  // namespace

int main() {
  std::printf("find_package(animlod) consumer:\n");
  simplify();
  select();
  pose();
  skin();
  std::printf("find_package(animlod) consumer: %s\n", failures == 0 ? "ok" : "FAILED");
  return failures == 0 ? 0 : 1;
}
