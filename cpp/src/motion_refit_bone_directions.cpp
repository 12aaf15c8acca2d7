// Bone directions of the motion re-fit (see the header); seeds/000, Eq. 7 held as hard
// constraints. A direction is the exponential map of its tangent plane at the start direction
// u0 (basis e1, e2): with w = s1 e1 + s2 e2 and t = |w|, u(s) = cos t u0 + (sin t / t) w, so
// du / ds_j = (sin t / t) (e_j - s_j u0) + ((t cos t - sin t) / t^3) s_j w (series below
// t = 1e-4). The chart is regular up to t = pi, the direction opposite the start.
#include "motion_refit_bone_directions.hpp"

#include <cmath>
#include <deque>

#include "motion_refit_detail.hpp"

namespace animlod::detail {

BoneDirections::BoneDirections(const MotionRefitProblem& problem, const std::vector<uint8_t>& candidate,
                               const std::vector<uint8_t>& kept_pairs, bool enabled)
    : direction_of_(problem.point_count, -1), jacobians_(problem.point_count) {
  if (!enabled) return;
  const size_t p = problem.point_count;
  std::vector<std::vector<std::pair<int32_t, int32_t>>> links(p);  // (neighbour, pair)
  for (size_t k = 0; k < problem.length_pair_count; ++k) {
    const int32_t a = problem.length_pairs[2 * k], b = problem.length_pairs[2 * k + 1];
    if (!kept_pairs[k] || !candidate[a] || !candidate[b]) continue;
    links[a].push_back({b, static_cast<int32_t>(k)});
    links[b].push_back({a, static_cast<int32_t>(k)});
  }
  // Breadth first from the root, then from the lowest point of every other tree: each point
  // reached hangs from the point it was reached from.
  std::vector<uint8_t> reached(p, 0);
  for (size_t first = 0; first < p; ++first) {
    if (reached[first] || links[first].empty()) continue;
    reached[first] = 1;
    std::deque<int32_t> queue{static_cast<int32_t>(first)};
    while (!queue.empty()) {
      const int32_t from = queue.front();
      queue.pop_front();
      for (const auto& [to, pair] : links[from]) {
        if (reached[to]) continue;
        reached[to] = 1;
        direction_of_[to] = static_cast<int32_t>(points_.size());
        points_.push_back(to);
        parents_.push_back(from);
        pairs_.push_back(pair);
        lengths_.push_back(problem.key_lengths[pair]);
        queue.push_back(to);
      }
    }
  }
  charts_.resize(points_.size());
}

void BoneDirections::set_start(const double* x, const double* original) {
  for (size_t i = 0; i < points_.size(); ++i) {
    const int32_t k = points_[i], up = parents_[i];
    double* u0 = charts_[i].data();
    double norm = 0.0;
    for (const double* at : {x, original}) {  // x's direction, else the original's
      for (int a = 0; a < 3; ++a) u0[a] = at[3 * k + a] - at[3 * up + a];
      norm = std::sqrt(u0[0] * u0[0] + u0[1] * u0[1] + u0[2] * u0[2]);
      if (norm > 0.0 && std::isfinite(norm)) break;
    }
    if (norm > 0.0 && std::isfinite(norm)) {
      for (int a = 0; a < 3; ++a) u0[a] /= norm;
    } else {
      u0[0] = 1.0, u0[1] = 0.0, u0[2] = 0.0;
    }
    tangent_basis(u0, u0 + 3, u0 + 6);
  }
}

void BoneDirections::place(size_t i, const double* s, double* x) {
  const double* u0 = charts_[i].data();
  const double* e[2] = {u0 + 3, u0 + 6};
  const double t2 = s[0] * s[0] + s[1] * s[1];
  const double t = std::sqrt(t2);
  const bool small = t < 1e-4;
  const double sinc = small ? 1.0 - t2 / 6.0 : std::sin(t) / t;
  const double slope = small ? -1.0 / 3.0 + t2 / 30.0 : (t * std::cos(t) - std::sin(t)) / (t2 * t);
  const double cosine = std::cos(t);
  const int32_t k = points_[i], up = parents_[i];
  const double b = lengths_[i];
  double w[3];
  for (int a = 0; a < 3; ++a) {
    w[a] = s[0] * e[0][a] + s[1] * e[1][a];
    x[3 * k + a] = x[3 * up + a] + b * (cosine * u0[a] + sinc * w[a]);
  }
  Matrix3& j = jacobians_[k];
  for (int a = 0; a < 3; ++a) {
    for (int c = 0; c < 2; ++c) j[3 * a + c] = b * (sinc * (e[c][a] - s[c] * u0[a]) + slope * s[c] * w[a]);
    j[3 * a + 2] = 0.0;
  }
}

void BoneDirections::coordinates(size_t i, const double* x, double* s) const {
  const double* u0 = charts_[i].data();
  const int32_t k = points_[i], up = parents_[i];
  double v[3], along = 0.0, across[2] = {0.0, 0.0};
  for (int a = 0; a < 3; ++a) v[a] = x[3 * k + a] - x[3 * up + a];
  for (int a = 0; a < 3; ++a) {
    along += v[a] * u0[a];
    across[0] += v[a] * u0[3 + a];
    across[1] += v[a] * u0[6 + a];
  }
  const double sine = std::hypot(across[0], across[1]);  // both scaled by |v|
  if (!(sine > 0.0)) {  // on the start's axis: the start, or (pi, 0) opposite it
    s[0] = along < 0.0 ? std::acos(-1.0) : 0.0, s[1] = 0.0;
    return;
  }
  const double angle = std::atan2(sine, along);
  s[0] = angle * across[0] / sine, s[1] = angle * across[1] / sine;
}

}  // namespace animlod::detail
