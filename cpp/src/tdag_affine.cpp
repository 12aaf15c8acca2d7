// Section 3 of Shamir and Pascucci 2001: separating the low-frequency (affine) from the
// high-frequency (residual) motion. For every frame t the 3 x 4 affine map A_t that best maps
// the base mesh P_0 onto P_t in the least-squares sense,
//   A_t = P_t P_0^T (P_0 P_0^T)^-1          (P homogeneous, 4 x V),
// and the residual mesh A_t^-1 P_t. Sums are accumulated in double about the base's centroid,
// which keeps the 4 x 4 normal matrix well conditioned far from the origin.
#include "animlod/tdag_affine.hpp"

#include <cmath>
#include <string>

#include <Eigen/Core>
#include <Eigen/LU>

namespace animlod {

namespace {

// Relative conditioning below which a linear part is treated as singular.
constexpr double kSingular = 1e-10;

Status check_mesh(const AnimatedMeshView& mesh) {
  if (mesh.frame_count == 0) return Status::error("frames: the mesh has no frames");
  if (mesh.vertex_count == 0) return Status::error("frames: the mesh has no vertices");
  const size_t per_frame = mesh.vertex_count * 3;
  for (size_t i = 0; i < mesh.frame_count * per_frame; ++i)
    if (!std::isfinite(mesh.frames[i]))
      return Status::error("frame " + std::to_string(i / per_frame) + ", vertex " +
                           std::to_string(i % per_frame / 3) + ": non-finite position");
  return Status::success();
}

// |det| against the cube of the mean squared column norm: scale-free.
bool well_conditioned(const Eigen::Matrix3d& m) {
  const double scale = m.squaredNorm() / 3.0;
  return scale > 0.0 && std::fabs(m.determinant()) > kSingular * std::pow(scale, 1.5);
}

}  // namespace

Status affine_split(const AnimatedMeshView& mesh, AffineBase base, AffineSplit& out) {
  return affine_split(mesh, nullptr, mesh.vertex_count, base, out);
}

Status affine_split(const AnimatedMeshView& mesh, const int32_t* vertices, size_t count, AffineBase base,
                    AffineSplit& out) {
  out = AffineSplit{};
  if (Status status = check_mesh(mesh); !status) return status;
  if (count == 0) return Status::error("vertices: none selected");
  for (size_t v = 0; vertices != nullptr && v < count; ++v)
    if (vertices[v] < 0 || static_cast<size_t>(vertices[v]) >= mesh.vertex_count)
      return Status::error("vertices: " + std::to_string(vertices[v]) + " outside [0, " +
                           std::to_string(mesh.vertex_count) + ")");
  const size_t frame_count = mesh.frame_count, vertex_count = count;
  auto point = [&](size_t frame, size_t v) {
    const size_t vertex = vertices != nullptr ? static_cast<size_t>(vertices[v]) : v;
    const float* p = mesh.frames + (frame * mesh.vertex_count + vertex) * 3;
    return Eigen::Vector3d(p[0], p[1], p[2]);
  };

  // The base mesh P_0 (V, 3), centred: q_v = p_v - c.
  std::vector<Eigen::Vector3d> centred(vertex_count, Eigen::Vector3d::Zero());
  for (size_t v = 0; v < vertex_count; ++v) {
    if (base == AffineBase::first) {
      centred[v] = point(0, v);
      continue;
    }
    for (size_t f = 0; f < frame_count; ++f) centred[v] += point(f, v);
    centred[v] /= static_cast<double>(frame_count);
  }
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& q : centred) centroid += q;
  centroid /= static_cast<double>(vertex_count);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // sum q q^T
  for (auto& q : centred) {
    q -= centroid;
    covariance += q * q.transpose();
  }
  // With centred coordinates the normal equations decouple: linear part L = (sum p q^T) C^-1,
  // translation = mean(p) - L c. A flat or degenerate base has a singular C.
  const bool base_ok = well_conditioned(covariance);
  Eigen::Matrix3d covariance_inverse = Eigen::Matrix3d::Identity();
  if (base_ok) covariance_inverse = covariance.inverse();

  out.maps.resize(frame_count * 12);
  out.residuals.resize(frame_count * vertex_count * 3);
  out.translation_only.assign(frame_count, 0);
  for (size_t f = 0; f < frame_count; ++f) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();  // sum p q^T
    for (size_t v = 0; v < vertex_count; ++v) {
      const Eigen::Vector3d p = point(f, v);
      mean += p;
      cross += p * centred[v].transpose();
    }
    mean /= static_cast<double>(vertex_count);
    Eigen::Matrix3d linear = cross * covariance_inverse;
    if (!base_ok || !well_conditioned(linear)) {
      linear.setIdentity();
      out.translation_only[f] = 1;
    }
    const Eigen::Vector3d translation = mean - linear * centroid;
    double* map = &out.maps[f * 12];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) map[r * 4 + c] = linear(r, c);
      map[r * 4 + 3] = translation(r);
    }
    // Residual: A_t^-1 p = L^-1 (p - translation).
    const Eigen::Matrix3d inverse = linear.inverse();
    for (size_t v = 0; v < vertex_count; ++v) {
      const Eigen::Vector3d r = inverse * (point(f, v) - translation);
      float* residual = &out.residuals[(f * vertex_count + v) * 3];
      for (int k = 0; k < 3; ++k) residual[k] = static_cast<float>(r(k));
    }
  }
  return Status::success();
}

void apply_affine(const double* map, const float* points, size_t count, float* out) {
  for (size_t i = 0; i < count; ++i) {
    const double x = points[3 * i], y = points[3 * i + 1], z = points[3 * i + 2];
    for (int r = 0; r < 3; ++r)
      out[3 * i + r] = static_cast<float>(map[r * 4] * x + map[r * 4 + 1] * y + map[r * 4 + 2] * z + map[r * 4 + 3]);
  }
}

}  // namespace animlod
