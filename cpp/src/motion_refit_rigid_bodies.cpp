// Rigid bodies of the motion re-fit (see the header); seeds/000, Eq. 7 held as hard constraints.
// A member sits at x_base + R(w) d_k with R(w) = exp([w]x) (Rodrigues), and
// d(R(w) d) / dw = -[R(w) d]x J_l(w), J_l the left Jacobian of SO(3):
// I + (1 - cos t) / t^2 [w]x + (t - sin t) / t^3 [w]x^2, t = |w| (series below t = 1e-4).
#include "motion_refit_rigid_bodies.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/QR>

#include "motion_refit_detail.hpp"

namespace animlod::detail {

namespace {

// A body's rows below this (scaled like the equalities, by 1 / L) count as held at the start:
// a feasible start's rounding (~1e-16) is left alone, so its solve is unchanged.
constexpr double kRigidTolerance = 1e-14;
constexpr int kRigidIterations = 30;

// [w]x as a row-major 3 x 3 matrix.
std::array<double, 9> cross_matrix(const double* w) {
  return {0.0, -w[2], w[1], w[2], 0.0, -w[0], -w[1], w[0], 0.0};
}

// Sine of the widest angle at its base below which a body lies along a line (about 3 degrees, as
// objective.py's _FLAT).
constexpr double kAlongALine = 0.05;

// Whether the held lengths `held` (rows of the body's set) put every member within kAlongALine
// of one line through `base`: no triangle of held lengths (base, a, b) opens wider at the base.
bool along_a_line(const MotionRefitProblem& problem, const std::vector<size_t>& held, int32_t base) {
  auto length = [&](int32_t a, int32_t b) {  // the held length between a and b, 0 if none
    for (size_t r : held) {
      if (r >= problem.length_pair_count) continue;
      const int32_t* pair = problem.length_pairs + 2 * r;
      if ((pair[0] == a && pair[1] == b) || (pair[0] == b && pair[1] == a)) return problem.key_lengths[r];
    }
    return 0.0;
  };
  bool triangle = false;
  for (size_t r : held) {
    if (r >= problem.length_pair_count) continue;
    const int32_t a = problem.length_pairs[2 * r], b = problem.length_pairs[2 * r + 1];
    const double la = length(base, a), lb = length(base, b), lab = problem.key_lengths[r];
    if (a == base || b == base || la == 0.0 || lb == 0.0) continue;
    const double cosine = std::clamp((la * la + lb * lb - lab * lab) / (2.0 * la * lb), -1.0, 1.0);
    if (std::sqrt(1.0 - cosine * cosine) > kAlongALine) return false;
    triangle = true;
  }
  return triangle;
}

}  // namespace

RigidBodies::RigidBodies(const MotionRefitProblem& problem, const std::vector<uint8_t>& excluded, bool enabled)
    : problem_(problem),
      body_of_(problem.point_count, -1),
      inner_equalities_(motion_refit_equality_count(problem), 0),
      inner_handed_(problem.handed_quad_count, 0),
      offsets_(3 * problem.point_count, 0.0),
      jacobians_(problem.point_count) {
  if (!enabled) return;
  const size_t p = problem.point_count;
  const std::vector<EqualityRow> rows = equality_rows(problem);
  std::vector<std::vector<int32_t>> children(p);  // child sides of each point's held lengths
  for (size_t k = 0; k < problem.length_pair_count; ++k)
    children[problem.length_pairs[2 * k + 1]].push_back(problem.length_pairs[2 * k]);

  std::vector<int32_t> in_set(p, 0);  // stamp: 1 + the candidate's base
  // 1 when every point of row r is in the candidate set.
  auto inside = [&](size_t r, int32_t stamp) {
    for (int c = 0; c < rows[r].width; ++c)
      if (in_set[rows[r].points[c]] != stamp) return false;
    return true;
  };
  std::vector<std::vector<size_t>> rows_of(p);  // equality rows touching each point
  for (size_t r = 0; r < rows.size(); ++r)
    for (int c = 0; c < rows[r].width; ++c) rows_of[rows[r].points[c]].push_back(r);

  for (size_t base = 0; base < p; ++base) {
    if (excluded[base] || children[base].size() < 2) continue;
    const int32_t stamp = static_cast<int32_t>(base) + 1;
    std::vector<int32_t> set;
    for (int32_t c : children[base])
      if (c != 0 && !excluded[c] && body_of_[c] < 0 && in_set[c] != stamp) set.push_back(c), in_set[c] = stamp;
    in_set[base] = stamp;
    // Keep the children tied to another child by a row inside the set, until none drops out.
    for (bool dropped = true; dropped;) {
      dropped = false;
      for (size_t i = 0; i < set.size(); ++i) {
        const int32_t c = set[i];
        const bool tied = std::any_of(rows_of[c].begin(), rows_of[c].end(), [&](size_t r) {
          if (!inside(r, stamp)) return false;
          for (int k = 0; k < rows[r].width; ++k)
            if (rows[r].points[k] != c && rows[r].points[k] != static_cast<int32_t>(base)) return true;
          return false;
        });
        if (tied) continue;
        in_set[c] = 0;
        set.erase(set.begin() + static_cast<long>(i));
        dropped = true;
        break;
      }
    }
    if (set.size() < 2) continue;
    std::vector<size_t> held;
    for (size_t r = 0; r < rows.size(); ++r)
      if (inside(r, stamp)) held.push_back(r);
    if (held.size() != 3 * set.size() - 3) continue;  // not a minimal rigid set: leave it to SLSQP
    const auto body = static_cast<int32_t>(bases_.size());
    bases_.push_back(static_cast<int32_t>(base));
    along_a_line_.push_back(along_a_line(problem, held, static_cast<int32_t>(base)) ? 1 : 0);
    std::sort(set.begin(), set.end());
    for (int32_t c : set) body_of_[c] = body;
    members_.push_back(set);
    for (size_t r : held) inner_equalities_[r] = 1;
    for (size_t k = 0; k < problem.handed_quad_count; ++k) {
      const int32_t* q = problem.handed_quads + 4 * k;
      if (std::all_of(q, q + 4, [&](int32_t point) { return in_set[point] == stamp; })) inner_handed_[k] = 1;
    }
  }

  // Bases before their bodies; a cycle (bases that are members of each other's bodies) cannot
  // be placed, so its bodies are dropped and their rows go back to SLSQP.
  std::vector<uint8_t> placed(bases_.size(), 0);
  for (bool progress = true; progress;) {
    progress = false;
    for (size_t b = 0; b < bases_.size(); ++b) {
      const int32_t owner = body_of_[bases_[b]];
      if (placed[b] || (owner >= 0 && !placed[owner])) continue;
      placed[b] = 1;
      order_.push_back(static_cast<int32_t>(b));
      progress = true;
    }
  }
  if (order_.size() == bases_.size()) {
    for (size_t r = 0; r < inner_equalities_.size(); ++r)
      if (inner_equalities_[r]) held_rows_.push_back(r);
    return;
  }
  std::fill(inner_equalities_.begin(), inner_equalities_.end(), uint8_t{0});
  std::fill(inner_handed_.begin(), inner_handed_.end(), uint8_t{0});
  std::fill(body_of_.begin(), body_of_.end(), -1);
  bases_.clear();
  members_.clear();
  along_a_line_.clear();
  order_.clear();
}

void RigidBodies::set_start(const double* x) {
  if (bases_.empty()) return;
  shape_.assign(x, x + 3 * problem_.point_count);
  make_rigid();
  turn_bases_.assign(bases_.size(), Matrix3{});
  for (size_t b = 0; b < bases_.size(); ++b) {
    Eigen::Vector3d line = Eigen::Vector3d::Zero();  // the farthest member's offset
    for (int32_t k : members_[b]) {
      for (int a = 0; a < 3; ++a) offsets_[3 * k + a] = shape_[3 * k + a] - shape_[3 * bases_[b] + a];
      const Eigen::Map<const Eigen::Vector3d> offset(&offsets_[3 * k]);
      if (offset.squaredNorm() > line.squaredNorm()) line = offset;
    }
    if (!along_a_line_[b] || !(line.squaredNorm() > 0.0)) continue;
    // Two axes across the line: turns about them move it, a turn about it moves nothing.
    line.normalize();
    Eigen::Index least = 0;
    line.cwiseAbs().minCoeff(&least);
    const Eigen::Vector3d first = line.cross(Eigen::Vector3d::Unit(least)).normalized();
    const Eigen::Vector3d second = line.cross(first);
    for (int i = 0; i < 3; ++i) turn_bases_[b][3 * i] = first(i), turn_bases_[b][3 * i + 1] = second(i);
  }
}

void RigidBodies::make_rigid() {
  const size_t p = problem_.point_count;
  const size_t m = inner_equalities_.size();
  values_.resize(m);
  auto held = [&] {  // every body's rows within tolerance (or not finite: left to the solve's check)
    double worst = 0.0;
    for (size_t r : held_rows_) worst = std::max(worst, std::abs(values_[r]));
    return !(worst > kRigidTolerance);
  };
  refit_equalities_frame(problem_, shape_.data(), values_.data(), nullptr);
  if (held()) return;  // a feasible start, the usual case
  std::vector<int32_t> columns;  // the members' coordinates
  for (size_t k = 0; k < p; ++k)
    if (body_of_[k] >= 0)
      for (int a = 0; a < 3; ++a) columns.push_back(static_cast<int32_t>(3 * k + a));
  const auto rows = static_cast<Eigen::Index>(held_rows_.size());
  const auto cols = static_cast<Eigen::Index>(columns.size());
  jacobian_.resize(m * 3 * p);
  for (int iteration = 0; iteration < kRigidIterations; ++iteration) {
    refit_equalities_frame(problem_, shape_.data(), values_.data(), jacobian_.data());
    if (held()) return;
    Eigen::MatrixXd j(rows, cols);
    Eigen::VectorXd residual(rows);
    for (Eigen::Index r = 0; r < rows; ++r) {
      residual(r) = -values_[held_rows_[r]];
      for (Eigen::Index c = 0; c < cols; ++c) j(r, c) = jacobian_[held_rows_[r] * 3 * p + columns[c]];
    }
    const Eigen::VectorXd step = j.completeOrthogonalDecomposition().solve(residual);
    for (Eigen::Index c = 0; c < cols; ++c) shape_[columns[c]] += step(c);
  }
}

void RigidBodies::place(size_t body, const double* variables, double* x) {
  // A body along a line turns about the two axes across it (turn_bases_ columns), others about
  // any axis.
  const Matrix3& across = turn_bases_[body];
  const bool line = along_a_line_[body] != 0;
  double w[3];
  for (int i = 0; i < 3; ++i)
    w[i] = line ? across[3 * i] * variables[0] + across[3 * i + 1] * variables[1] : variables[i];
  const double t2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
  const double t = std::sqrt(t2);
  // sin t / t, (1 - cos t) / t^2, (t - sin t) / t^3
  const bool small = t < 1e-4;
  const double s = small ? 1.0 - t2 / 6.0 : std::sin(t) / t;
  const double c = small ? 0.5 - t2 / 24.0 : (1.0 - std::cos(t)) / t2;
  const double e = small ? 1.0 / 6.0 - t2 / 120.0 : (t - std::sin(t)) / (t2 * t);
  const std::array<double, 9> wx = cross_matrix(w);
  std::array<double, 9> wx2{}, left{};  // [w]x^2, J_l
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 3; ++k) wx2[3 * i + j] += wx[3 * i + k] * wx[3 * k + j];
      left[3 * i + j] = (i == j ? 1.0 : 0.0) + c * wx[3 * i + j] + e * wx2[3 * i + j];
    }
  const double* origin = x + 3 * bases_[body];
  for (int32_t k : members_[body]) {
    const double* d = offsets_.data() + 3 * k;
    double v[3];  // R d = d + s [w]x d + c [w]x^2 d
    for (int i = 0; i < 3; ++i)
      v[i] = d[i] + s * (wx[3 * i] * d[0] + wx[3 * i + 1] * d[1] + wx[3 * i + 2] * d[2]) +
             c * (wx2[3 * i] * d[0] + wx2[3 * i + 1] * d[1] + wx2[3 * i + 2] * d[2]);
    for (int i = 0; i < 3; ++i) x[3 * k + i] = origin[i] + v[i];
    const std::array<double, 9> vx = cross_matrix(v);
    Matrix3 j{};  // d x_k / d w = -[v]x J_l
    for (int i = 0; i < 3; ++i)
      for (int col = 0; col < 3; ++col)
        for (int k2 = 0; k2 < 3; ++k2) j[3 * i + col] -= vx[3 * i + k2] * left[3 * k2 + col];
    if (!line) {
      jacobians_[k] = j;
      continue;
    }
    Matrix3& derivative = jacobians_[k];  // d x_k / d variables: j times the axes across
    for (int i = 0; i < 3; ++i)
      for (int col = 0; col < 3; ++col)
        derivative[3 * i + col] =
            j[3 * i] * across[col] + j[3 * i + 1] * across[3 + col] + j[3 * i + 2] * across[6 + col];
  }
}

}  // namespace animlod::detail
