// Motion features (Yang et al. 2019, sections "Rotation connected graph" and "Weight
// allocation"):
//   g_i = max_f CVDA_i^{(f-1)-f}, the largest change of edge i's dihedral angle between
//         consecutive frames;
//   THR = (sum_i g_i) / n over the n interior edges (the paper: over all edges; boundary
//         edges have no dihedral angle and are features anyway, so they are left out);
//   edge i is connected when g_i > THR and g_i > 1 degree; boundary edges are connected;
//   the connected components of connected edges are the features, and every vertex of a
//   feature with w vertices gets weight w (others 1), the vertex weights of Eq. 6.
#include "animlod/motion_features.hpp"

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "edge_table.hpp"
#include "mesh_validation_detail.hpp"
#include "union_find.hpp"

namespace animlod {

namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d position(const float* frame, int32_t vertex) {
  const float* p = frame + 3 * static_cast<size_t>(vertex);  // 3 V may exceed int32
  return Eigen::Vector3f(p[0], p[1], p[2]).cast<double>();
}

// Unnormalised face normals (twice the area) of one frame: (M, 3).
void face_normals(const AnimatedMeshView& mesh, const float* frame, std::vector<Eigen::Vector3d>& normals) {
  for (size_t f = 0; f < mesh.face_count; ++f) {
    const int32_t* v = mesh.faces + 3 * f;
    const Eigen::Vector3d p0 = position(frame, v[0]);
    normals[f] = (position(frame, v[1]) - p0).cross(position(frame, v[2]) - p0);
  }
}

// Signed angle between the normals of the faces on the two sides of the edge, about the edge
// direction (0 for a flat pair), so that folding either way is told apart.
double signed_dihedral(const Eigen::Vector3d& n0, const Eigen::Vector3d& n1, const Eigen::Vector3d& edge) {
  const double length = edge.norm();
  if (length == 0.0) return 0.0;
  return std::atan2(n0.cross(n1).dot(edge) / length, n0.dot(n1));
}

double wrapped_difference(double a, double b) {
  double d = std::fabs(a - b);
  return d > kPi ? 2.0 * kPi - d : d;
}

// g_i for every edge (0 on boundary edges).
std::vector<float> angle_changes(const AnimatedMeshView& mesh, const detail::EdgeTable& edges) {
  const size_t edge_count = edges.size();
  std::vector<float> change(edge_count, 0.0f);
  std::vector<double> previous(edge_count, 0.0);
  std::vector<Eigen::Vector3d> normals(mesh.face_count);
  for (size_t t = 0; t < mesh.frame_count; ++t) {
    const float* frame = mesh.frames + t * mesh.vertex_count * 3;
    face_normals(mesh, frame, normals);
    for (size_t e = 0; e < edge_count; ++e) {
      if (edges.is_boundary(e)) continue;
      const auto [a, b] = edges.vertices[e];
      const double angle = signed_dihedral(normals[edges.faces[e][0]], normals[edges.faces[e][1]],
                                           position(frame, b) - position(frame, a));
      if (t > 0) change[e] = std::max(change[e], static_cast<float>(wrapped_difference(angle, previous[e])));
      previous[e] = angle;
    }
  }
  return change;
}

}  // namespace

Status compute_motion_features(const AnimatedMeshView& mesh, const MotionFeatureOptions& options,
                               MotionFeatures& out) {
  detail::EdgeTable edges;
  if (Status status = detail::validate_and_build_edges(mesh, edges); !status) return status;
  if (!(options.feature_threshold >= 0.0) || !(options.min_angle_change >= 0.0))
    return Status::error("motion features: feature_threshold and min_angle_change must be >= 0 radians");
  const size_t edge_count = edges.size();

  // g_i and THR.
  out.angle_change = angle_changes(mesh, edges);
  double sum = 0.0;
  size_t interior = 0;
  for (size_t e = 0; e < edge_count; ++e) {
    if (edges.is_boundary(e)) continue;
    sum += out.angle_change[e];
    ++interior;
  }
  out.threshold = options.feature_threshold > 0.0 ? options.feature_threshold
                                                  : (interior ? sum / static_cast<double>(interior) : 0.0);

  // Connected edges and their components (the rotation connected graphs).
  out.edges.resize(2 * edge_count);
  out.connected.assign(edge_count, 0);
  detail::UnionFind components(mesh.vertex_count);
  std::vector<uint8_t> in_feature(mesh.vertex_count, 0);
  for (size_t e = 0; e < edge_count; ++e) {
    const auto [a, b] = edges.vertices[e];
    out.edges[2 * e] = a;
    out.edges[2 * e + 1] = b;
    const double g = out.angle_change[e];
    const bool connected = edges.is_boundary(e) ? options.boundary_is_feature
                                                : g > out.threshold && g > options.min_angle_change;
    if (!connected) continue;
    out.connected[e] = 1;
    components.unite(a, b);
    in_feature[a] = in_feature[b] = 1;
  }

  // Number the features by their lowest vertex (the union-find root) and weigh them.
  out.vertex_feature.assign(mesh.vertex_count, -1);
  out.feature_sizes.clear();
  std::vector<int32_t> feature_of_root(mesh.vertex_count, -1);
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    if (!in_feature[v]) continue;
    const int32_t root = components.find(static_cast<int32_t>(v));
    if (feature_of_root[root] < 0) {
      feature_of_root[root] = static_cast<int32_t>(out.feature_sizes.size());
      out.feature_sizes.push_back(0);
    }
    out.vertex_feature[v] = feature_of_root[root];
    ++out.feature_sizes[feature_of_root[root]];
  }
  out.vertex_weights.assign(mesh.vertex_count, 1.0f);
  for (size_t v = 0; v < mesh.vertex_count; ++v)
    if (out.vertex_feature[v] >= 0) out.vertex_weights[v] = static_cast<float>(out.feature_sizes[out.vertex_feature[v]]);
  return Status::success();
}

}  // namespace animlod
