// Motion LoD re-fit terms (seeds/000, Section 5.2): E = alpha Ed + beta Es + gamma Ea (Eq. 5),
// Ed (Eq. 6) the squared distance of every non-root point to its original position, Es (Eq. 7)
// the squared change of each held length against the key posture, Ea (Eq. 8) the squared change
// of cos theta (Eq. 4) at each frozen joint. Lengths are divided by L so that E is unit-free.
// The same formulas, vectorised over frames, are python/animlod/motion_lod/objective.py (the
// reference the tests compare against).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "animlod/motion_refit.hpp"
#include "motion_refit_detail.hpp"

namespace animlod {

namespace {

using Vec3 = std::array<double, 3>;

Vec3 load(const double* x, int32_t point) { return {x[3 * point], x[3 * point + 1], x[3 * point + 2]}; }
Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
void add_to(double* target, int32_t point, const Vec3& v, double factor) {
  for (int k = 0; k < 3; ++k) target[3 * point + k] += factor * v[k];
}

// |a - b| and the unit direction (zero at length 0).
double length_and_unit(const double* x, int32_t a, int32_t b, Vec3& unit) {
  const Vec3 d = sub(load(x, a), load(x, b));
  const double length = std::sqrt(dot(d, d));
  for (int k = 0; k < 3; ++k) unit[k] = length > 0.0 ? d[k] / length : 0.0;
  return length;
}

// cos theta at the middle point of (parent, joint, child) (Eq. 4) and its gradients with respect
// to the parent, joint and child positions; with `curvature` also the three 3 x 3 pieces of its
// Hessian (AngleTerm::hessian_block maps them to the points). With u = parent - joint,
// v = child - joint, their unit vectors e, f, a = 1/|u|, b = 1/|v| and c = cos theta = e.f:
//   d/du = a (f - c e),  d/dv = b (e - c f),
//   d2/du2 = a^2 (3c e e^T - e f^T - f e^T - c I),  d2/dv2 = b^2 (3c f f^T - e f^T - f e^T - c I),
//   d2/du dv = a b (I - e e^T - f f^T + c e f^T).
double cosine(const double* x, const int32_t* triple, double* gradient, bool curvature, double* huu, double* hvv,
              double* huv) {
  const Vec3 joint = load(x, triple[1]);
  const Vec3 u = sub(load(x, triple[0]), joint);
  const Vec3 v = sub(load(x, triple[2]), joint);
  const double a = 1.0 / std::sqrt(dot(u, u));
  const double b = 1.0 / std::sqrt(dot(v, v));
  const Vec3 e = {u[0] * a, u[1] * a, u[2] * a};
  const Vec3 f = {v[0] * b, v[1] * b, v[2] * b};
  const double c = dot(e, f);
  for (int k = 0; k < 3; ++k) {
    gradient[k] = a * (f[k] - c * e[k]);
    gradient[6 + k] = b * (e[k] - c * f[k]);
    gradient[3 + k] = -(gradient[k] + gradient[6 + k]);
  }
  if (!curvature) return c;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const double eye = i == j ? 1.0 : 0.0;
      const double mixed = e[i] * f[j] + f[i] * e[j];
      huu[3 * i + j] = a * a * (3.0 * c * e[i] * e[j] - mixed - c * eye);
      hvv[3 * i + j] = b * b * (3.0 * c * f[i] * f[j] - mixed - c * eye);
      huv[3 * i + j] = a * b * (eye - e[i] * e[j] - f[i] * f[j] + c * e[i] * f[j]);
    }
  return c;
}

// Negative eigenvalues of a symmetric 9 x 9 matrix (row-major) set to zero.
void clip_to_positive_semidefinite(double* block) {
  Eigen::Map<Eigen::Matrix<double, 9, 9, Eigen::RowMajor>> m(block);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> eigen(m);
  if (eigen.eigenvalues().minCoeff() >= 0.0) return;
  const auto values = eigen.eigenvalues().cwiseMax(0.0);
  m = eigen.eigenvectors() * values.asDiagonal() * eigen.eigenvectors().transpose();
}

// det[a - p, b - p, c - p] of a quad (p, a, b, c) and its gradients with respect to p, a, b, c.
double volume(const double* x, const int32_t* quad, std::array<Vec3, 4>& grads) {
  const Vec3 p = load(x, quad[0]);
  const Vec3 u = sub(load(x, quad[1]), p);
  const Vec3 v = sub(load(x, quad[2]), p);
  const Vec3 w = sub(load(x, quad[3]), p);
  grads[1] = cross(v, w);
  grads[2] = cross(w, u);
  grads[3] = cross(u, v);
  for (int k = 0; k < 3; ++k) grads[0][k] = -(grads[1][k] + grads[2][k] + grads[3][k]);
  return dot(u, grads[1]);
}

std::string point_range(size_t point_count) { return "[0, " + std::to_string(point_count) + ")"; }

Status check_indices(const int32_t* indices, size_t rows, size_t width, size_t point_count, const char* name) {
  if (rows > 0 && indices == nullptr) return Status::error(std::string(name) + ": no data for " + std::to_string(rows) + " rows");
  for (size_t r = 0; r < rows; ++r) {
    for (size_t k = 0; k < width; ++k) {
      const int32_t point = indices[r * width + k];
      if (point < 0 || static_cast<size_t>(point) >= point_count)
        return Status::error(std::string(name) + "[" + std::to_string(r) + "]: point " + std::to_string(point) +
                             " is outside " + point_range(point_count));
      for (size_t other = 0; other < k; ++other)
        if (indices[r * width + other] == point)
          return Status::error(std::string(name) + "[" + std::to_string(r) + "]: point " + std::to_string(point) +
                               " appears twice");
    }
  }
  return Status::success();
}

enum class Expect { positive, unit_interval, non_zero, finite };

Status check_values(const double* values, size_t count, const char* name, Expect expect) {
  if (count > 0 && values == nullptr) return Status::error(std::string(name) + ": no data");
  for (size_t i = 0; i < count; ++i) {
    const double v = values[i];
    const bool bad = !std::isfinite(v) || (expect == Expect::positive && !(v > 0.0)) ||
                     (expect == Expect::unit_interval && std::abs(v) > 1.0 + 1e-9) ||
                     (expect == Expect::non_zero && v == 0.0);
    if (bad) {
      const char* expected = expect == Expect::positive        ? "a finite positive number"
                             : expect == Expect::unit_interval ? "a cosine in [-1, 1]"
                             : expect == Expect::non_zero      ? "a finite non-zero volume"
                                                               : "a finite number";
      return Status::error(std::string(name) + "[" + std::to_string(i) + "] = " + std::to_string(v) + ": expected " +
                           expected);
    }
  }
  return Status::success();
}

}  // namespace

size_t motion_refit_equality_count(const MotionRefitProblem& problem) {
  return problem.length_pair_count + 3 * problem.coincident_pair_count + problem.flat_quad_count;
}

Status validate_motion_refit_problem(const MotionRefitProblem& problem) {
  if (problem.point_count < 2)
    return Status::error("point_count: needs the root and at least one other point, got " +
                         std::to_string(problem.point_count));
  if (!(std::isfinite(problem.length_scale) && problem.length_scale > 0.0))
    return Status::error("length_scale: expected a finite positive length, got " + std::to_string(problem.length_scale));
  if (!(std::isfinite(problem.distance_weight) && problem.distance_weight > 0.0))
    return Status::error("weights: distance must be positive, got " + std::to_string(problem.distance_weight));
  if (!(std::isfinite(problem.string_weight) && problem.string_weight >= 0.0))
    return Status::error("weights: string must be a finite non-negative number, got " +
                         std::to_string(problem.string_weight));
  if (!(std::isfinite(problem.angle_weight) && problem.angle_weight >= 0.0))
    return Status::error("weights: angle must be a finite non-negative number, got " +
                         std::to_string(problem.angle_weight));
  const size_t p = problem.point_count;
  Status s = check_indices(problem.length_pairs, problem.length_pair_count, 2, p, "length_pairs");
  if (s) s = check_values(problem.key_lengths, problem.length_pair_count, "key_lengths", Expect::positive);
  if (s) s = check_indices(problem.coincident_pairs, problem.coincident_pair_count, 2, p, "coincident_pairs");
  if (s) s = check_indices(problem.handed_quads, problem.handed_quad_count, 4, p, "handed_quads");
  if (s) s = check_values(problem.key_volumes, problem.handed_quad_count, "key_volumes", Expect::non_zero);
  if (s) s = check_indices(problem.flat_quads, problem.flat_quad_count, 4, p, "flat_quads");
  if (s) s = check_values(problem.flat_volumes, problem.flat_quad_count, "flat_volumes", Expect::finite);
  if (s) s = check_values(problem.flat_areas, problem.flat_quad_count, "flat_areas", Expect::positive);
  if (s) s = check_indices(problem.angle_triples, problem.angle_triple_count, 3, p, "angle_triples");
  if (s) s = check_values(problem.key_cosines, problem.angle_triple_count, "key_cosines", Expect::unit_interval);
  return s;
}

namespace detail {

double refit_objective_frame(const MotionRefitProblem& problem, const double* x, const double* original,
                             double* gradient) {
  const size_t p = problem.point_count;
  const double scale2 = problem.length_scale * problem.length_scale;
  const double wd = problem.distance_weight / scale2;
  const double ws = problem.string_weight / scale2;
  if (gradient) std::fill(gradient, gradient + 3 * p, 0.0);

  double value = 0.0;  // Ed, Eq. 6 (root excluded)
  for (size_t i = 3; i < 3 * p; ++i) {
    const double delta = x[i] - original[i];
    value += wd * delta * delta;
    if (gradient) gradient[i] = 2.0 * wd * delta;
  }
  for (size_t k = 0; k < problem.length_pair_count; ++k) {  // Es, Eq. 7
    const int32_t a = problem.length_pairs[2 * k], b = problem.length_pairs[2 * k + 1];
    Vec3 unit;
    const double excess = length_and_unit(x, a, b, unit) - problem.key_lengths[k];
    value += ws * excess * excess;
    if (gradient) {
      add_to(gradient, a, unit, 2.0 * ws * excess);
      add_to(gradient, b, unit, -2.0 * ws * excess);
    }
  }
  for (size_t k = 0; k < problem.coincident_pair_count; ++k) {  // Es at zero key length
    const int32_t a = problem.coincident_pairs[2 * k], b = problem.coincident_pairs[2 * k + 1];
    const Vec3 d = sub(load(x, a), load(x, b));
    value += ws * dot(d, d);
    if (gradient) {
      add_to(gradient, a, d, 2.0 * ws);
      add_to(gradient, b, d, -2.0 * ws);
    }
  }
  for (size_t k = 0; k < problem.angle_triple_count; ++k) {  // Ea, Eq. 8
    const AngleTerm term(problem, x, k, false);
    value += term.value();
    if (!gradient) continue;
    double term_gradient[9];
    term.gradient(term_gradient);
    const int32_t* triple = problem.angle_triples + 3 * k;
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) gradient[3 * triple[c] + a] += term_gradient[3 * c + a];
  }
  if (gradient) gradient[0] = gradient[1] = gradient[2] = 0.0;
  return value;
}

std::vector<EqualityRow> equality_rows(const MotionRefitProblem& problem) {
  std::vector<EqualityRow> rows;
  rows.reserve(motion_refit_equality_count(problem));
  for (size_t k = 0; k < problem.length_pair_count; ++k)
    rows.push_back({{problem.length_pairs[2 * k], problem.length_pairs[2 * k + 1], 0, 0}, 2});
  for (size_t k = 0; k < problem.coincident_pair_count; ++k)
    for (int axis = 0; axis < 3; ++axis)
      rows.push_back({{problem.coincident_pairs[2 * k], problem.coincident_pairs[2 * k + 1], 0, 0}, 2});
  for (size_t k = 0; k < problem.flat_quad_count; ++k) {
    const int32_t* q = problem.flat_quads + 4 * k;
    rows.push_back({{q[0], q[1], q[2], q[3]}, 4});
  }
  return rows;
}

void refit_equalities_frame(const MotionRefitProblem& problem, const double* x, double* values, double* jacobian) {
  const size_t p = problem.point_count;
  const double inverse = 1.0 / problem.length_scale;
  const size_t m = motion_refit_equality_count(problem);
  if (jacobian) std::fill(jacobian, jacobian + m * 3 * p, 0.0);
  size_t row = 0;
  for (size_t k = 0; k < problem.length_pair_count; ++k, ++row) {
    const int32_t a = problem.length_pairs[2 * k], b = problem.length_pairs[2 * k + 1];
    Vec3 unit;
    values[row] = (length_and_unit(x, a, b, unit) - problem.key_lengths[k]) * inverse;
    if (jacobian) {
      add_to(jacobian + row * 3 * p, a, unit, inverse);
      add_to(jacobian + row * 3 * p, b, unit, -inverse);
    }
  }
  for (size_t k = 0; k < problem.coincident_pair_count; ++k) {
    const int32_t a = problem.coincident_pairs[2 * k], b = problem.coincident_pairs[2 * k + 1];
    for (int axis = 0; axis < 3; ++axis, ++row) {
      values[row] = (x[3 * a + axis] - x[3 * b + axis]) * inverse;
      if (jacobian) {
        jacobian[row * 3 * p + 3 * a + axis] += inverse;
        jacobian[row * 3 * p + 3 * b + axis] -= inverse;
      }
    }
  }
  for (size_t k = 0; k < problem.flat_quad_count; ++k, ++row) {
    const int32_t* quad = problem.flat_quads + 4 * k;
    const double scale = inverse / problem.flat_areas[k];
    std::array<Vec3, 4> grads;
    values[row] = (volume(x, quad, grads) - problem.flat_volumes[k]) * scale;
    if (jacobian)
      for (int c = 0; c < 4; ++c) add_to(jacobian + row * 3 * p, quad[c], grads[c], scale);
  }
  if (jacobian)
    for (size_t r = 0; r < m; ++r) std::fill(jacobian + r * 3 * p, jacobian + r * 3 * p + 3, 0.0);
}

void refit_handedness_frame(const MotionRefitProblem& problem, const double* x, double* values, double* jacobian) {
  const size_t p = problem.point_count;
  const double scale3 = problem.length_scale * problem.length_scale * problem.length_scale;
  if (jacobian) std::fill(jacobian, jacobian + problem.handed_quad_count * 3 * p, 0.0);
  for (size_t k = 0; k < problem.handed_quad_count; ++k) {
    const int32_t* quad = problem.handed_quads + 4 * k;
    const double sign = (problem.key_volumes[k] > 0.0 ? -1.0 : 1.0) / scale3;
    std::array<Vec3, 4> grads;
    values[k] = sign * volume(x, quad, grads);
    if (jacobian) {
      for (int c = 0; c < 4; ++c) add_to(jacobian + k * 3 * p, quad[c], grads[c], sign);
      std::fill(jacobian + k * 3 * p, jacobian + k * 3 * p + 3, 0.0);
    }
  }
}

void refit_hessian_frame(const MotionRefitProblem& problem, const double* x, bool positive_semidefinite,
                         double* matrix) {
  const size_t n = 3 * (problem.point_count - 1);
  const double scale2 = problem.length_scale * problem.length_scale;
  std::fill(matrix, matrix + n * n, 0.0);
  // Adds w * block (3 x 3, row-major) to the (a, b) block, skipping the root (not a variable).
  auto add_block = [&](int32_t a, int32_t b, const double* block, double w) {
    if (a == 0 || b == 0) return;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) matrix[(3 * (a - 1) + i) * n + 3 * (b - 1) + j] += w * block[3 * i + j];
  };
  auto add_pair = [&](int32_t a, int32_t b, const double* block, double w) {
    add_block(a, a, block, w);
    add_block(b, b, block, w);
    add_block(a, b, block, -w);
    add_block(b, a, block, -w);
  };
  const double wd = 2.0 * problem.distance_weight / scale2;  // Ed
  for (size_t i = 0; i < n; ++i) matrix[i * n + i] += wd;
  const double ws = 2.0 * problem.string_weight / scale2;
  for (size_t k = 0; k < problem.length_pair_count; ++k) {  // Es: u u^T + (r / |d|) (I - u u^T)
    const int32_t a = problem.length_pairs[2 * k], b = problem.length_pairs[2 * k + 1];
    Vec3 unit;
    const double length = length_and_unit(x, a, b, unit);
    double stretch = length > 0.0 ? (length - problem.key_lengths[k]) / length : 0.0;
    if (positive_semidefinite) stretch = std::max(stretch, 0.0);
    double block[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        block[3 * i + j] = unit[i] * unit[j] + stretch * ((i == j ? 1.0 : 0.0) - unit[i] * unit[j]);
    add_pair(a, b, block, ws);
  }
  const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (size_t k = 0; k < problem.coincident_pair_count; ++k)
    add_pair(problem.coincident_pairs[2 * k], problem.coincident_pairs[2 * k + 1], identity, ws);
  for (size_t k = 0; k < problem.angle_triple_count; ++k) {  // Ea
    const int32_t* triple = problem.angle_triples + 3 * k;
    const AngleTerm term(problem, x, k, true);
    double block[81];  // 9 x 9 over the triple's (parent, joint, child) coordinates
    for (int pi = 0; pi < 3; ++pi)
      for (int pj = 0; pj < 3; ++pj) {
        double sub_block[9];
        term.hessian_block(pi, pj, sub_block);
        for (int i = 0; i < 3; ++i) std::copy_n(sub_block + 3 * i, 3, block + 9 * (3 * pi + i) + 3 * pj);
      }
    if (positive_semidefinite) clip_to_positive_semidefinite(block);
    for (int pi = 0; pi < 3; ++pi)
      for (int pj = 0; pj < 3; ++pj) {
        double sub_block[9];
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) sub_block[3 * i + j] = block[9 * (3 * pi + i) + 3 * pj + j];
        add_block(triple[pi], triple[pj], sub_block, 1.0);
      }
  }
}

AngleTerm::AngleTerm(const MotionRefitProblem& problem, const double* x, size_t k, bool curvature)
    : weight_(problem.angle_weight) {
  residual_ = cosine(x, problem.angle_triples + 3 * k, cosine_gradient_, curvature, huu_, hvv_, huv_) -
              problem.key_cosines[k];
}

void AngleTerm::gradient(double* out) const {
  for (int i = 0; i < 9; ++i) out[i] = 2.0 * weight_ * residual_ * cosine_gradient_[i];
}

void AngleTerm::hessian_block(int row, int column, double* block) const {
  // cos's Hessian over the points, by u = p - j, v = c - j: pp = huu, cc = hvv, pc = huv,
  // pj = -huu - huv, cj = -hvv - huv^T, jj = huu + hvv + huv + huv^T, the others their
  // transposes. The diagonal blocks read their lower triangle (index l, lt its mirror), so that
  // the matrix is symmetric to the last bit.
  double h[9];
  auto fill = [&h](auto entry) {  // entry(ij, ji): one loop per block kind, unrolled
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) h[3 * i + j] = entry(3 * i + j, 3 * j + i);
  };
  switch (3 * row + column) {
    case 0: fill([&](int ij, int ji) { return huu_[std::max(ij, ji)]; }); break;
    case 1: fill([&](int ij, int) { return -huu_[ij] - huv_[ij]; }); break;
    case 2: fill([&](int ij, int) { return huv_[ij]; }); break;
    case 3: fill([&](int, int ji) { return -huu_[ji] - huv_[ji]; }); break;
    case 4:
      fill([&](int ij, int ji) {
        const int l = std::max(ij, ji), lt = std::min(ij, ji);
        return huu_[l] + hvv_[l] + huv_[l] + huv_[lt];
      });
      break;
    case 5: fill([&](int ij, int ji) { return -hvv_[ji] - huv_[ij]; }); break;
    case 6: fill([&](int, int ji) { return huv_[ji]; }); break;
    case 7: fill([&](int ij, int ji) { return -hvv_[ij] - huv_[ji]; }); break;
    default: fill([&](int ij, int ji) { return hvv_[std::max(ij, ji)]; }); break;
  }
  const double* gr = cosine_gradient_ + 3 * row;
  const double* gc = cosine_gradient_ + 3 * column;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) block[3 * i + j] = 2.0 * weight_ * (gr[i] * gc[j] + residual_ * h[3 * i + j]);
}

}  // namespace detail

Status motion_refit_objective(const MotionRefitProblem& problem, const double* x, const double* original,
                              size_t frame_count, double* out_values, double* out_gradient) {
  const Status status = validate_motion_refit_problem(problem);
  if (!status) return status;
  const size_t stride = 3 * problem.point_count;
  for (size_t f = 0; f < frame_count; ++f)
    out_values[f] = detail::refit_objective_frame(problem, x + f * stride, original + f * stride,
                                                  out_gradient ? out_gradient + f * stride : nullptr);
  return Status::success();
}

Status motion_refit_equalities(const MotionRefitProblem& problem, const double* x, size_t frame_count,
                               double* out_values, double* out_jacobian) {
  const Status status = validate_motion_refit_problem(problem);
  if (!status) return status;
  const size_t stride = 3 * problem.point_count;
  const size_t m = motion_refit_equality_count(problem);
  for (size_t f = 0; f < frame_count; ++f)
    detail::refit_equalities_frame(problem, x + f * stride, out_values + f * m,
                                   out_jacobian ? out_jacobian + f * m * stride : nullptr);
  return Status::success();
}

Status motion_refit_handedness(const MotionRefitProblem& problem, const double* x, size_t frame_count,
                               double* out_values, double* out_jacobian) {
  const Status status = validate_motion_refit_problem(problem);
  if (!status) return status;
  const size_t stride = 3 * problem.point_count;
  const size_t h = problem.handed_quad_count;
  for (size_t f = 0; f < frame_count; ++f)
    detail::refit_handedness_frame(problem, x + f * stride, out_values + f * h,
                                   out_jacobian ? out_jacobian + f * h * stride : nullptr);
  return Status::success();
}

}  // namespace animlod
