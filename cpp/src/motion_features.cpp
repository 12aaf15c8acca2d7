// Motion features (Yang et al. 2019, sections "Rotation connected graph" and "Weight
// allocation"):
//   g_i = max_f CVDA_i^{(f-1)-f}, the largest change of edge i's dihedral angle between
//         consecutive frames;
//   THR = (sum_i g_i) / n over the n interior edges (the paper: over all edges; boundary
//         edges have no dihedral angle and are features anyway, so they are left out);
//   edge i is connected when g_i > THR and g_i > 1 degree; boundary edges are connected;
//   the connected components of connected edges are the features, and every vertex of a
//   feature with w vertices gets weight w (others 1), the vertex weights of Eq. 6.
// That is FeatureWeighting::paper. The default, FeatureWeighting::amplitude, keeps the features
// and Eq. 6 but measures an edge's motion by the range of its dihedral angle over the sequence,
// puts the threshold above the measured spread of those ranges, and bounds the weight (see
// motion_features.hpp for why).
#include "animlod/motion_features.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "edge_table.hpp"
#include "mesh_validation_detail.hpp"
#include "union_find.hpp"
#include "worker_threads.hpp"

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

// b - a wrapped into [-pi, pi]: the signed change of an angle between two frames.
double signed_wrapped_difference(double b, double a) {
  double d = b - a;
  if (d > kPi) d -= 2.0 * kPi;
  else if (d < -kPi) d += 2.0 * kPi;
  return d;
}

// Edges per thread below which another thread costs more than it saves.
constexpr size_t kEdgesPerThread = 4096;

// g_i (the largest change between consecutive frames) and a_i (the range of the unwrapped
// dihedral angle over all frames) for every edge, 0 on boundary edges. Edges are independent:
// each thread takes a range of them through every frame (with its own face normals).
void angle_changes(const AnimatedMeshView& mesh, const detail::EdgeTable& edges, std::vector<float>& change,
                   std::vector<float>& amplitude) {
  const size_t edge_count = edges.size();
  change.assign(edge_count, 0.0f);
  amplitude.assign(edge_count, 0.0f);
  const size_t workers =
      std::min<size_t>(thread_limit(), edge_count / kEdgesPerThread);
  detail::run_in_ranges(edge_count, workers, [&](size_t begin, size_t end, size_t) {
    const size_t count = end - begin;
    std::vector<double> previous(count, 0.0), unwrapped(count, 0.0), lowest(count, 0.0), highest(count, 0.0);
    std::vector<Eigen::Vector3d> normals(mesh.face_count);
    for (size_t t = 0; t < mesh.frame_count; ++t) {
      const float* frame = mesh.frames + t * mesh.vertex_count * 3;
      face_normals(mesh, frame, normals);
      for (size_t e = begin; e < end; ++e) {
        if (edges.is_boundary(e)) continue;
        const size_t i = e - begin;
        const auto [a, b] = edges.vertices[e];
        const double angle = signed_dihedral(normals[edges.faces[e][0]], normals[edges.faces[e][1]],
                                             position(frame, b) - position(frame, a));
        if (t > 0) {
          const double step = signed_wrapped_difference(angle, previous[i]);
          change[e] = std::max(change[e], static_cast<float>(std::fabs(step)));
          unwrapped[i] += step;
          lowest[i] = std::min(lowest[i], unwrapped[i]);
          highest[i] = std::max(highest[i], unwrapped[i]);
        }
        previous[i] = angle;
      }
    }
    for (size_t e = begin; e < end; ++e) amplitude[e] = static_cast<float>(highest[e - begin] - lowest[e - begin]);
  });
}

// The median of `values` (reordered), 0 when empty.
double median_of(std::vector<double>& values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  const double upper = *middle;
  if (values.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), middle));
}

// FeatureWeighting::amplitude's adaptive threshold: median + noise_mads * MAD of the interior
// edges' amplitudes.
double amplitude_threshold(const std::vector<float>& amplitude, const detail::EdgeTable& edges,
                           double noise_mads) {
  std::vector<double> values;
  values.reserve(amplitude.size());
  for (size_t e = 0; e < amplitude.size(); ++e)
    if (!edges.is_boundary(e)) values.push_back(amplitude[e]);
  const double median = median_of(values);
  for (double& value : values) value = std::fabs(value - median);
  return median + noise_mads * median_of(values);
}

}  // namespace

Status check_motion_feature_options(const MotionFeatureOptions& options) {
  if (!(options.feature_threshold >= 0.0) || !(options.min_angle_change >= 0.0))
    return Status::error("motion features: feature_threshold and min_angle_change must be >= 0 radians");
  if (!(options.max_feature_weight >= 1.0) || !std::isfinite(options.max_feature_weight))
    return Status::error("motion features: max_feature_weight must be finite and >= 1");
  if (!(options.noise_mads >= 0.0) || !std::isfinite(options.noise_mads))
    return Status::error("motion features: noise_mads must be finite and >= 0");
  return Status::success();
}

Status compute_motion_features(const AnimatedMeshView& mesh, const MotionFeatureOptions& options,
                               MotionFeatures& out) {
  if (Status status = check_motion_feature_options(options); !status) return status;
  detail::EdgeTable edges;
  if (Status status = detail::validate_and_build_edges(mesh, edges); !status) return status;
  const size_t edge_count = edges.size();
  const bool paper = options.feature_weighting == FeatureWeighting::paper;

  // g_i, a_i and the threshold on the weighting's measure of motion (THR or T).
  angle_changes(mesh, edges, out.angle_change, out.amplitude);
  const std::vector<float>& motion = paper ? out.angle_change : out.amplitude;
  if (options.feature_threshold > 0.0) {
    out.threshold = options.feature_threshold;
  } else if (paper) {
    double sum = 0.0;
    size_t interior = 0;
    for (size_t e = 0; e < edge_count; ++e) {
      if (edges.is_boundary(e)) continue;
      sum += out.angle_change[e];
      ++interior;
    }
    out.threshold = interior ? sum / static_cast<double>(interior) : 0.0;
  } else {
    out.threshold = std::max(amplitude_threshold(out.amplitude, edges, options.noise_mads), options.min_angle_change);
  }

  // Connected edges and their components (the rotation connected graphs).
  out.edges.resize(2 * edge_count);
  out.connected.assign(edge_count, 0);
  detail::UnionFind components(mesh.vertex_count);
  std::vector<uint8_t> in_feature(mesh.vertex_count, 0);
  for (size_t e = 0; e < edge_count; ++e) {
    const auto [a, b] = edges.vertices[e];
    out.edges[2 * e] = a;
    out.edges[2 * e + 1] = b;
    const double g = motion[e];
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
  if (paper) {
    for (size_t v = 0; v < mesh.vertex_count; ++v)
      if (out.vertex_feature[v] >= 0)
        out.vertex_weights[v] = static_cast<float>(out.feature_sizes[out.vertex_feature[v]]);
    return Status::success();
  }
  // Amplitude: each vertex takes the strongest of its connected interior edges, so that a vertex
  // outside every feature keeps exactly 1.
  std::vector<double> strength(mesh.vertex_count, 0.0);
  for (size_t e = 0; e < edge_count; ++e) {
    if (!out.connected[e] || edges.is_boundary(e)) continue;
    const double excess = out.threshold > 0.0 ? (out.amplitude[e] - out.threshold) / out.threshold : 1.0;
    const double s = std::clamp(excess, 0.0, 1.0);
    for (const int32_t v : edges.vertices[e]) strength[v] = std::max(strength[v], s);
  }
  for (size_t v = 0; v < mesh.vertex_count; ++v)
    if (strength[v] > 0.0) out.vertex_weights[v] = static_cast<float>(1.0 + (options.max_feature_weight - 1.0) * strength[v]);
  return Status::success();
}

}  // namespace animlod
