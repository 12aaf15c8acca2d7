// Placement on the height map and the camera paths (crowd_scene.hpp; the motion LoD paper,
// seeds/000 Section 3: a height map of the movable region; Section 6.4: two navigation paths).
#include "crowd_scene.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

namespace crowd {

namespace {
constexpr float kPi = 3.14159265358979f;
}

CrowdScene::CrowdScene(const std::vector<Asset>& assets, const CrowdOptions& options) {
  height_ = 0.0f;
  for (const Asset& asset : assets) height_ = std::max(height_, asset.height());
  if (!(height_ > 0.0f)) height_ = 1.0f;
  relief_ = 0.3f * height_;
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(options.count))));
  const float spacing = options.spacing * height_;
  half_extent_ = 0.5f * static_cast<float>(side) * spacing;
  std::mt19937 random(options.seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  placements_.reserve(static_cast<size_t>(options.count));
  for (int i = 0; i < options.count; ++i) {
    Placement p;
    p.asset = i % static_cast<int>(assets.size());
    const Asset& asset = assets[static_cast<size_t>(p.asset)];
    p.clip = static_cast<int>(unit(random) * static_cast<float>(asset.clip_names.size())) %
             static_cast<int>(asset.clip_names.size());
    const float jitter_x = (unit(random) - 0.5f) * 0.6f, jitter_z = (unit(random) - 0.5f) * 0.6f;
    const float x = -half_extent_ + (static_cast<float>(i % side) + 0.5f + jitter_x) * spacing;
    const float z = -half_extent_ + (static_cast<float>(i / side) + 0.5f + jitter_z) * spacing;
    p.position = glm::vec3(x, ground_height(x, z) - asset.bounds_min.y, z);
    p.yaw = unit(random) * 2.0f * kPi;
    p.phase = unit(random) * 10.0f;  // seconds; wrapped by each clip's duration
    placements_.push_back(p);
  }
}

CrowdScene::CrowdScene(std::vector<Placement> placements, float half_extent, float character_height)
    : placements_(std::move(placements)), half_extent_(half_extent), height_(character_height) {}

float CrowdScene::ground_height(float x, float z) const {
  const float k1 = 2.0f * kPi / (12.0f * height_), k2 = 2.0f * kPi / (17.0f * height_), k3 = 2.0f * kPi / (29.0f * height_);
  return relief_ * (std::sin(k1 * x) * std::cos(k2 * z) + 0.5f * std::sin(k3 * (x + z)));
}

Camera CrowdScene::camera(CameraPath path, float u, float aspect, float fov_radians) const {
  const float e = half_extent_, h = height_;
  Camera c;
  switch (path) {
    case CameraPath::nav1: {  // walk through the crowd on a gentle S curve at head height
      auto at = [&](float s) { return glm::vec2(0.25f * e * std::sin(2.0f * kPi * s), (e + 2.0f * h) * (1.0f - 2.0f * s)); };
      const glm::vec2 here = at(u);
      const float s = std::min(u, 0.98f);
      const glm::vec2 direction = glm::normalize(at(s + 0.02f) - at(s));
      c.eye = glm::vec3(here.x, ground_height(here.x, here.y) + 1.2f * h, here.y);
      const glm::vec2 look = here + 10.0f * h * direction;
      c.target = glm::vec3(look.x, ground_height(look.x, look.y) + 0.4f * h, look.y);
      break;
    }
    case CameraPath::nav2: {  // circle over the crowd, looking down at its centre
      const float angle = 0.25f * kPi + kPi * u;
      c.eye = glm::vec3(0.8f * e * std::cos(angle), 0.7f * e + 6.0f * h, 0.8f * e * std::sin(angle));
      c.target = glm::vec3(0.0f, 0.0f, 0.0f);
      break;
    }
    case CameraPath::pullback: {  // from just in front of the first row to far behind it
      const float distance = 2.5f * h + u * (1.5f * e + 30.0f * h);
      c.eye = glm::vec3(0.0f, 0.8f * h + 0.15f * distance, e + distance);
      c.target = glm::vec3(0.0f, 0.6f * h, e - 0.5f * distance);
      break;
    }
  }
  return make_camera(c.eye, c.target, fov_radians, aspect, 0.05f * h, 12.0f * e + 100.0f * h);
}

Camera make_camera(const glm::vec3& eye, const glm::vec3& target, float fov_radians, float aspect, float near_plane,
                   float far_plane) {
  Camera c;
  c.eye = eye;
  c.target = target;
  c.view = glm::lookAt(eye, target, glm::vec3(0.0f, 1.0f, 0.0f));
  c.projection = glm::perspective(fov_radians, aspect, near_plane, far_plane);
  // Frustum planes from the rows of projection * view (Gribb and Hartmann).
  const glm::mat4 m = glm::transpose(c.projection * c.view);
  c.planes = {m[3] + m[0], m[3] - m[0], m[3] + m[1], m[3] - m[1], m[3] + m[2], m[3] - m[2]};
  for (glm::vec4& plane : c.planes) plane /= glm::length(glm::vec3(plane));
  return c;
}

void CrowdScene::ground_mesh(std::vector<float>& positions, std::vector<uint32_t>& indices) const {
  const int cells = 96;
  const float extent = 1.5f * half_extent_ + 60.0f * height_;
  positions.clear();
  indices.clear();
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i) {
      const float x = -extent + 2.0f * extent * static_cast<float>(i) / cells;
      const float z = -extent + 2.0f * extent * static_cast<float>(j) / cells;
      positions.insert(positions.end(), {x, ground_height(x, z), z});
    }
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      const auto a = static_cast<uint32_t>(j * (cells + 1) + i), b = a + 1, c = a + cells + 1, d = c + 1;
      indices.insert(indices.end(), {a, c, b, b, c, d});
    }
}

bool sphere_visible(const Camera& camera, const glm::vec3& center, float radius) {
  for (const glm::vec4& plane : camera.planes)
    if (glm::dot(glm::vec3(plane), center) + plane.w < -radius) return false;
  return true;
}

}  // namespace crowd
