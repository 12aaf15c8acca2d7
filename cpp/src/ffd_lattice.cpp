// Rational free-form deformation over Bernstein lattices (seeds/004, Section 3.2.2: "3 x 3 x 3 = 27
// control points are defined along the bounding box of each region"; RFFD assigns weights to
// the control points), and the least-squares 2x2x2 lattice of Section 4.2.2 (Figure 8).
//
// Every function is a loop over points; the per-point work is the tensor product of three
// Bernstein bases (de Casteljau's triangle, stable for any degree up to 15).
#include "animlod/ffd_lattice.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace animlod {

namespace {

constexpr const char* kAxisNames[3] = {"S", "T", "U"};

// Bernstein values B_i^{count-1}(x), i < count, by de Casteljau's triangle.
void bernstein(size_t count, double x, double* out) {
  const double y = 1.0 - x;
  out[0] = 1.0;
  for (size_t j = 1; j < count; ++j) {
    out[j] = x * out[j - 1];
    for (size_t i = j - 1; i > 0; --i) out[i] = y * out[i] + x * out[i - 1];
    out[0] *= y;
  }
}

double clamp01(float value) { return std::min(1.0, std::max(0.0, static_cast<double>(value))); }

Status check_size(const size_t size[3], const std::string& element) {
  for (int axis = 0; axis < 3; ++axis)
    if (size[axis] < 2 || size[axis] > kMaxLatticeSize)
      return Status::error(element + ": " + std::to_string(size[axis]) + " control points along axis " +
                           kAxisNames[axis] + ", expected 2 to " + std::to_string(kMaxLatticeSize));
  return Status::success();
}

Status check_weights(const double* weights, size_t count, size_t first_index, const std::string& element) {
  if (weights == nullptr) return Status::success();
  for (size_t c = 0; c < count; ++c)
    if (!(std::isfinite(weights[c]) && weights[c] > 0.0))
      return Status::error(element + ": weight of control point " + std::to_string(first_index + c) + " is " +
                           std::to_string(weights[c]) + ", expected a finite value > 0");
  return Status::success();
}

Status check_local(const float* local, size_t point_count) {
  for (size_t p = 0; p < point_count; ++p)
    for (int axis = 0; axis < 3; ++axis)
      if (!std::isfinite(local[3 * p + axis]))
        return Status::error("local coordinates: point " + std::to_string(p) + " is not finite");
  return Status::success();
}

// The rational basis R_c(s, t, u) = w_c B_c / sum w B of one point (c in lattice order), into
// `basis` (l m n values). Returns false when the denominator vanishes (cannot happen for
// positive weights and clamped coordinates; kept as a guard).
bool rational_basis(const size_t size[3], const double* weights, const float* local, double* basis) {
  std::array<double, kMaxLatticeSize> bs{}, bt{}, bu{};
  bernstein(size[0], clamp01(local[0]), bs.data());
  bernstein(size[1], clamp01(local[1]), bt.data());
  bernstein(size[2], clamp01(local[2]), bu.data());
  double total = 0.0;
  size_t c = 0;
  for (size_t i = 0; i < size[0]; ++i)
    for (size_t j = 0; j < size[1]; ++j) {
      const double st = bs[i] * bt[j];
      for (size_t k = 0; k < size[2]; ++k, ++c) {
        const double value = st * bu[k] * (weights ? weights[c] : 1.0);
        basis[c] = value;
        total += value;
      }
    }
  if (!(total > 0.0)) return false;
  if (weights)
    for (size_t q = 0; q < c; ++q) basis[q] /= total;
  return true;
}

// rational_basis for a lattice size known at compile time (the common 3x3x3 and 2x2x2): the
// same arithmetic with every loop bound constant, so the compiler unrolls it.
template <size_t L, size_t M, size_t N>
bool rational_basis_fixed(const double* weights, const float* local, double* basis) {
  double bs[L], bt[M], bu[N];
  bernstein(L, clamp01(local[0]), bs);
  bernstein(M, clamp01(local[1]), bt);
  bernstein(N, clamp01(local[2]), bu);
  double total = 0.0;
  for (size_t i = 0; i < L; ++i)
    for (size_t j = 0; j < M; ++j)
      for (size_t k = 0; k < N; ++k) {
        const size_t c = (i * M + j) * N + k;
        const double value = bs[i] * bt[j] * bu[k] * (weights ? weights[c] : 1.0);
        basis[c] = value;
        total += value;
      }
  if (!(total > 0.0)) return false;
  if (weights)
    for (size_t c = 0; c < L * M * N; ++c) basis[c] /= total;
  return true;
}

bool any_rational_basis(const size_t size[3], const double* weights, const float* local, double* basis) {
  if (size[0] == 3 && size[1] == 3 && size[2] == 3) return rational_basis_fixed<3, 3, 3>(weights, local, basis);
  if (size[0] == 2 && size[1] == 2 && size[2] == 2) return rational_basis_fixed<2, 2, 2>(weights, local, basis);
  return rational_basis(size, weights, local, basis);
}

}  // namespace

Status ffd_local_coordinates(const LatticeBox& box, const float* points, size_t point_count, float* out_local) {
  // Phase 1: check the box. An axis is degenerate when its length is below 1e-12 of the
  // longest; the box is flat when its volume is below 1e-9 of the product of the lengths.
  Eigen::Matrix3d axes;
  double scale = 0.0;
  for (int a = 0; a < 3; ++a) {
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(box.axes[a][d]) || !std::isfinite(box.origin[d]))
        return Status::error(std::string("lattice box: axis ") + kAxisNames[a] + " or the origin is not finite");
      axes(d, a) = box.axes[a][d];
    }
    scale = std::max(scale, axes.col(a).norm());
  }
  for (int a = 0; a < 3; ++a)
    if (!(axes.col(a).norm() > 1e-12 * scale))
      return Status::error(std::string("lattice box: axis ") + kAxisNames[a] + " is degenerate (length " +
                           std::to_string(axes.col(a).norm()) + "); the box needs extent in every direction");
  const double volume = std::abs(axes.determinant());
  if (!(volume > 1e-9 * axes.col(0).norm() * axes.col(1).norm() * axes.col(2).norm()))
    return Status::error("lattice box: degenerate, axes S, T and U lie in one plane (volume " + std::to_string(volume) +
                         "); the box needs extent in every direction");
  // Phase 2: p - origin = A (s, t, u) for every point.
  const Eigen::Matrix3d inverse = axes.inverse();
  const Eigen::Vector3d origin(box.origin[0], box.origin[1], box.origin[2]);
  for (size_t p = 0; p < point_count; ++p) {
    const Eigen::Vector3d point(points[3 * p], points[3 * p + 1], points[3 * p + 2]);
    if (!point.allFinite()) return Status::error("points: point " + std::to_string(p) + " is not finite");
    const Eigen::Vector3d local = inverse * (point - origin);
    for (int d = 0; d < 3; ++d) out_local[3 * p + d] = static_cast<float>(local[d]);
  }
  return Status::success();
}

Status ffd_evaluate(const LatticeView& lattice, const float* local, size_t point_count, float* out) {
  if (Status status = check_size(lattice.size, "lattice"); !status) return status;
  if (lattice.control_points == nullptr) return Status::error("lattice: no control points given");
  const size_t controls = lattice.size[0] * lattice.size[1] * lattice.size[2];
  if (Status status = check_weights(lattice.weights, controls, 0, "lattice"); !status) return status;
  if (Status status = check_local(local, point_count); !status) return status;
  std::vector<double> basis(controls);
  for (size_t p = 0; p < point_count; ++p) {
    if (!rational_basis(lattice.size, lattice.weights, local + 3 * p, basis.data()))
      return Status::error("lattice: rational basis vanishes at point " + std::to_string(p));
    double sum[3] = {0.0, 0.0, 0.0};
    for (size_t c = 0; c < controls; ++c)
      for (int d = 0; d < 3; ++d) sum[d] += basis[c] * lattice.control_points[3 * c + d];
    for (int d = 0; d < 3; ++d) out[3 * p + d] = static_cast<float>(sum[d]);
  }
  return Status::success();
}

Status ffd_displace(const LatticeSetView& lattices, const float* rest, const float* local,
                    const int32_t* vertex_lattice, size_t vertex_count, float* out) {
  // Phase 1: sizes, offsets and weights of every lattice.
  const size_t lattice_count = lattices.lattice_count;
  std::vector<size_t> offsets(lattice_count + 1, 0);
  for (size_t r = 0; r < lattice_count; ++r) {
    size_t size[3];
    for (int axis = 0; axis < 3; ++axis) {
      const int32_t value = lattices.sizes[3 * r + axis];
      size[axis] = value < 0 ? 0 : static_cast<size_t>(value);
    }
    const std::string element = "lattice " + std::to_string(r);
    if (Status status = check_size(size, element); !status) return status;
    offsets[r + 1] = offsets[r] + size[0] * size[1] * size[2];
  }
  const size_t controls = offsets[lattice_count];
  if (controls > 0 && lattices.displacements == nullptr) return Status::error("lattices: no displacements given");
  for (size_t r = 0; r < lattice_count; ++r) {
    const double* weights = lattices.weights ? lattices.weights + offsets[r] : nullptr;
    if (Status status = check_weights(weights, offsets[r + 1] - offsets[r], offsets[r], "lattice " + std::to_string(r));
        !status)
      return status;
  }
  for (size_t v = 0; v < vertex_count; ++v)
    if (vertex_lattice[v] < -1 || vertex_lattice[v] >= static_cast<int64_t>(lattice_count))
      return Status::error("vertex_lattice: vertex " + std::to_string(v) + " names lattice " +
                           std::to_string(vertex_lattice[v]) + ", expected -1 to " +
                           std::to_string(static_cast<int64_t>(lattice_count) - 1));  // -1 to -1 without lattices

  // Phase 2: per vertex, its rational basis once, then every frame's displacement.
  const size_t frame_stride = 3 * vertex_count;
  std::vector<double> basis(kMaxLatticeSize * kMaxLatticeSize * kMaxLatticeSize);
  for (size_t v = 0; v < vertex_count; ++v) {
    const int32_t r = vertex_lattice[v];
    if (r < 0) {
      for (size_t f = 0; f < lattices.frame_count; ++f)
        for (int d = 0; d < 3; ++d) out[f * frame_stride + 3 * v + d] = rest[3 * v + d];
      continue;
    }
    const size_t size[3] = {static_cast<size_t>(lattices.sizes[3 * r]), static_cast<size_t>(lattices.sizes[3 * r + 1]),
                            static_cast<size_t>(lattices.sizes[3 * r + 2])};
    const size_t first = offsets[r], count = offsets[r + 1] - offsets[r];
    if (!any_rational_basis(size, lattices.weights ? lattices.weights + first : nullptr, local + 3 * v, basis.data()))
      return Status::error("lattice " + std::to_string(r) + ": rational basis vanishes at vertex " + std::to_string(v));
    for (size_t f = 0; f < lattices.frame_count; ++f) {
      const double* delta = lattices.displacements + 3 * (f * controls + first);
      double sum[3] = {0.0, 0.0, 0.0};
      for (size_t c = 0; c < count; ++c)
        for (int d = 0; d < 3; ++d) sum[d] += basis[c] * delta[3 * c + d];
      for (int d = 0; d < 3; ++d) out[f * frame_stride + 3 * v + d] = static_cast<float>(rest[3 * v + d] + sum[d]);
    }
  }
  return Status::success();
}

Status ffd_fit(const size_t size[3], const double* weights, const float* local, const float* targets,
               size_t point_count, const double* prior, double* out_control_points, const FfdFitOptions& options) {
  if (Status status = check_size(size, "lattice"); !status) return status;
  if (point_count == 0) return Status::error("fit: no points to fit the lattice to");
  if (!(std::isfinite(options.smoothness) && options.smoothness >= 0.0 && std::isfinite(options.ridge) &&
        options.ridge >= 0.0))
    return Status::error("fit: smoothness and ridge must be finite and >= 0");
  const size_t controls = size[0] * size[1] * size[2];
  if (Status status = check_weights(weights, controls, 0, "lattice"); !status) return status;
  if (Status status = check_local(local, point_count); !status) return status;
  if (prior != nullptr)
    for (size_t q = 0; q < 3 * controls; ++q)
      if (!std::isfinite(prior[q])) return Status::error("prior: control point " + std::to_string(q / 3) + " is not finite");

  // Phase 1: rows of the data term, the rational basis of each point (X_P = A P is linear in P).
  const double scale = static_cast<double>(point_count) / static_cast<double>(controls);
  const double smooth = std::sqrt(options.smoothness * scale), ridge = std::sqrt(options.ridge * scale);
  size_t second_differences = 0;
  for (int axis = 0; axis < 3; ++axis)
    if (size[axis] >= 3) second_differences += (size[axis] - 2) * (controls / size[axis]);
  const size_t rows = point_count + (smooth > 0.0 ? second_differences : 0) + (ridge > 0.0 ? controls : 0);
  Eigen::MatrixXd design = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(controls));
  Eigen::MatrixXd right = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(rows), 3);
  std::vector<double> basis(controls);
  for (size_t p = 0; p < point_count; ++p) {
    const auto row = static_cast<Eigen::Index>(p);
    if (!rational_basis(size, weights, local + 3 * p, basis.data()))
      return Status::error("lattice: rational basis vanishes at point " + std::to_string(p));
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(targets[3 * p + d]))
        return Status::error("targets: point " + std::to_string(p) + " is not finite");
      right(row, d) = targets[3 * p + d];
    }
    for (size_t c = 0; c < controls; ++c) {
      design(row, static_cast<Eigen::Index>(c)) = basis[c];
      if (prior != nullptr)  // the correction fits what the prior leaves
        for (int d = 0; d < 3; ++d) right(row, d) -= basis[c] * prior[3 * c + d];
    }
  }
  // Phase 2: regularisation rows on the correction Q: Q_{i-1} - 2 Q_i + Q_{i+1} along every
  // line, then Q itself.
  auto row = static_cast<Eigen::Index>(point_count);
  if (smooth > 0.0) {
    const size_t stride[3] = {size[1] * size[2], size[2], 1};
    for (int axis = 0; axis < 3; ++axis) {
      if (size[axis] < 3) continue;
      for (size_t c = 0; c < controls; ++c) {
        const size_t index = (c / stride[axis]) % size[axis];
        if (index == 0 || index + 1 == size[axis]) continue;
        design(row, static_cast<Eigen::Index>(c - stride[axis])) = smooth;
        design(row, static_cast<Eigen::Index>(c)) = -2.0 * smooth;
        design(row, static_cast<Eigen::Index>(c + stride[axis])) = smooth;
        ++row;
      }
    }
  }
  if (ridge > 0.0)
    for (size_t c = 0; c < controls; ++c, ++row) design(row, static_cast<Eigen::Index>(c)) = ridge;
  // Phase 3: least squares, least norm where the system leaves freedom; P = prior + Q.
  const Eigen::MatrixXd solution = design.completeOrthogonalDecomposition().solve(right);
  for (size_t c = 0; c < controls; ++c)
    for (int d = 0; d < 3; ++d)
      out_control_points[3 * c + d] = (prior ? prior[3 * c + d] : 0.0) + solution(static_cast<Eigen::Index>(c), d);
  return Status::success();
}

}  // namespace animlod
