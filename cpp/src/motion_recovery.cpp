// Recovery of a level's world rotations from re-fitted positions (motion_recovery.hpp). The
// quaternion operations are python/animlod/rotations.py's, operation for operation, so that the
// swing-aimed joints come out as the numpy version computed them; the best-fit rotation is an
// SVD (Eigen's here, LAPACK's there), equal to rounding.
#include "animlod/motion_recovery.hpp"

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "animlod/pose.hpp"

namespace animlod {

namespace {

struct Quaternion {
  double x, y, z, w;
};

Quaternion load(const double* q) { return {q[0], q[1], q[2], q[3]}; }

// Hamilton product a * b (b first).
Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

Quaternion conjugate(const Quaternion& q) { return {-q.x, -q.y, -q.z, q.w}; }

Eigen::Vector3d cross(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

double norm(const Eigen::Vector3d& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// v + w t + u x t with t = 2 u x v (u, w: the quaternion's vector and scalar parts).
Eigen::Vector3d rotate(const Quaternion& q, const Eigen::Vector3d& v) {
  const Eigen::Vector3d u(q.x, q.y, q.z);
  const Eigen::Vector3d t = 2.0 * cross(u, v);
  const Eigen::Vector3d c = cross(u, t);
  return {v[0] + q.w * t[0] + c[0], v[1] + q.w * t[1] + c[1], v[2] + q.w * t[2] + c[2]};
}

// The smallest rotation turning `from` towards `to`: identity where either is zero, a half turn
// about a perpendicular axis where they are opposite.
Quaternion swing(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  const double from_length = norm(from), to_length = norm(to);
  if (from_length == 0.0 || to_length == 0.0) return {0.0, 0.0, 0.0, 1.0};
  const Eigen::Vector3d a = from / std::max(from_length, 1e-300), b = to / std::max(to_length, 1e-300);
  const Eigen::Vector3d axis = cross(a, b);
  Quaternion q{axis[0], axis[1], axis[2], 1.0 + (a[0] * b[0] + a[1] * b[1] + a[2] * b[2])};
  if (std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w) < 1e-12) {
    const Eigen::Vector3d helper = std::abs(a[0]) < 0.9 ? Eigen::Vector3d(1.0, 0.0, 0.0) : Eigen::Vector3d(0.0, 1.0, 0.0);
    const Eigen::Vector3d half_turn = cross(a, helper);
    const double length = norm(half_turn);
    q = {half_turn[0] / length, half_turn[1] / length, half_turn[2] / length, 0.0};
  }
  const double length = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  return {q.x / length, q.y / length, q.z / length, q.w / length};
}

// The rotation R minimising sum_i |R a_i - d_i|^2 (Kabsch), as a quaternion with w >= 0.
Quaternion best_fit_rotation(const Eigen::Matrix3d& covariance) {  // sum_i d_i a_i^T
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0.0) u.col(2) *= -1.0;  // a rotation, not a reflection
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> rotation = u * svd.matrixV().transpose();
  double q[4];
  quaternions_from_matrices(rotation.data(), 1, q);
  return load(q);
}

Status validate(const AimedSkeleton& skeleton, size_t frame_count, const double* original_world,
                const double* targets, const double* translations) {
  const size_t k = skeleton.joint_count;
  if (Status status = validate_parents(skeleton.parents, k); !status.ok) return status;
  for (size_t j = 0; j < k; ++j) {
    if (skeleton.aim_offsets[j + 1] < skeleton.aim_offsets[j])
      return Status::error("aim_offsets[" + std::to_string(j + 1) + "]: decreasing");
    for (int32_t a = skeleton.aim_offsets[j]; a < skeleton.aim_offsets[j + 1]; ++a) {
      const int32_t child = skeleton.aim_children[a];
      const std::string where = "aim_children[" + std::to_string(a) + "]: ";
      if (child <= 0 || static_cast<size_t>(child) >= k || skeleton.parents[child] != static_cast<int32_t>(j))
        return Status::error(where + std::to_string(child) + " is not a child of joint " + std::to_string(j));
      if (skeleton.translating[child])
        return Status::error(where + "joint " + std::to_string(child) + " translates: it cannot aim its parent");
    }
  }
  const auto finite = [&](const double* values, size_t width, const char* name) {
    for (size_t i = 0; i < frame_count * k * width; ++i)
      if (!std::isfinite(values[i]))
        return Status::error(std::string(name) + "[" + std::to_string(i / width / k) + ", " +
                             std::to_string(i / width % k) + "]: not finite");
    return Status::success();
  };
  if (Status s = finite(original_world, 4, "original_world"); !s.ok) return s;
  if (Status s = finite(targets, 3, "targets"); !s.ok) return s;
  return finite(translations, 3, "translations");
}

}  // namespace

Status recover_world_rotations(const AimedSkeleton& skeleton, size_t frame_count, const double* original_world,
                               const double* targets, double* translations, double* out_world) {
  if (Status s = validate(skeleton, frame_count, original_world, targets, translations); !s.ok) return s;
  const size_t k = skeleton.joint_count;
  std::vector<Eigen::Vector3d> placed(k);  // where forward kinematics has put each joint
  for (size_t t = 0; t < frame_count; ++t) {
    const double* frame_targets = targets + 3 * k * t;
    double* frame_translations = translations + 3 * k * t;
    double* world = out_world + 4 * k * t;
    const auto target = [&](size_t j) { return Eigen::Vector3d(frame_targets + 3 * j); };
    const auto offset = [&](size_t j) { return Eigen::Vector3d(frame_translations + 3 * j); };
    for (size_t j = 0; j < k; ++j) {
      if (skeleton.parents[j] < 0) {  // a root is where the re-fit put it
        placed[j] = target(j);
      } else {
        const auto parent = static_cast<size_t>(skeleton.parents[j]);
        const Quaternion parent_world = load(world + 4 * parent);
        if (skeleton.translating[j]) {  // no fixed bone: the translation follows the re-fit
          const Eigen::Vector3d local = rotate(conjugate(parent_world), target(j) - placed[parent]);
          std::copy(local.data(), local.data() + 3, frame_translations + 3 * j);
        }
        placed[j] = placed[parent] + rotate(parent_world, offset(j));
      }
      Quaternion rotation = load(original_world + 4 * (k * t + j));
      const int32_t first = skeleton.aim_offsets[j], last = skeleton.aim_offsets[j + 1];
      if (last - first == 1) {
        const auto child = static_cast<size_t>(skeleton.aim_children[first]);
        rotation = multiply(swing(rotate(rotation, offset(child)), target(child) - placed[j]), rotation);
      } else if (last - first > 1) {
        Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
        for (int32_t a = first; a < last; ++a) {
          const auto child = static_cast<size_t>(skeleton.aim_children[a]);
          covariance += (target(child) - placed[j]) * rotate(rotation, offset(child)).transpose();
        }
        rotation = multiply(best_fit_rotation(covariance), rotation);
      }
      double* out = world + 4 * j;
      out[0] = rotation.x, out[1] = rotation.y, out[2] = rotation.z, out[3] = rotation.w;
    }
  }
  return Status::success();
}

}  // namespace animlod
