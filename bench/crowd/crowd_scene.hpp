// The crowd's world: characters placed on a ground height map (the paper's depth map of the
// movable region, seeds/000 Section 3, here a smooth procedural terrain), each with its own
// chain, clip, phase and heading, and a camera flown along a deterministic path.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "crowd_options.hpp"
#include "lod_asset.hpp"

namespace crowd {

struct Placement {
  int asset = 0;         // index into the loaded chains (files)
  int clip = 0;          // original clip index of that asset
  float phase = 0.0f;    // seconds into the clip at time 0
  glm::vec3 position{0.0f};  // where the character's rest-pose origin stands
  float yaw = 0.0f;      // heading, radians about +y
};

struct Camera {
  glm::vec3 eye{0.0f}, target{0.0f, 0.0f, -1.0f};
  glm::mat4 view{1.0f}, projection{1.0f};
  std::array<glm::vec4, 6> planes{};  // frustum planes (inside: dot(plane, (p, 1)) >= 0)
};

class CrowdScene {
 public:
  // Places options.count characters on a square field sized by the largest character and
  // options.spacing; deterministic in options.seed.
  CrowdScene(const std::vector<Asset>& assets, const CrowdOptions& options);
  // A hand-built scene (tests): these placements on a flat field of the given size.
  CrowdScene(std::vector<Placement> placements, float half_extent, float character_height);

  float ground_height(float x, float z) const;
  const std::vector<Placement>& placements() const { return placements_; }
  float half_extent() const { return half_extent_; }    // the field is [-e, e] x [-e, e]
  float character_height() const { return height_; }  // the tallest asset's rest height

  // The camera at fraction u in [0, 1] of `path`, for a viewport of `aspect` (width / height).
  Camera camera(CameraPath path, float u, float aspect, float fov_radians) const;

  // The ground as a grid mesh (positions (V, 3), triangle indices) over the field plus a margin.
  void ground_mesh(std::vector<float>& positions, std::vector<uint32_t>& indices) const;

 private:
  std::vector<Placement> placements_;
  float half_extent_ = 1.0f;
  float height_ = 1.0f;
  float relief_ = 0.0f;  // amplitude of the height map
};

// A perspective camera at `eye` looking at `target` (+y up) with its frustum planes.
Camera make_camera(const glm::vec3& eye, const glm::vec3& target, float fov_radians, float aspect, float near_plane,
                   float far_plane);

// Whether a sphere touches the frustum.
bool sphere_visible(const Camera& camera, const glm::vec3& center, float radius);

}  // namespace crowd
