// The `cumulative` ranking's greedy freezes (cumulative_ranking.hpp). Every cost is a sum over a
// candidate's subtree and the frames, so one step costs O(stale pairs x frames), and the whole
// ranking O(J x pairs x frames) at worst: Xbot's 67 joints and 150 frames took 0.5 s as numpy
// array operations per step, most of it gathering per-pair copies of the moves.
#include "animlod/cumulative_ranking.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "animlod/pose.hpp"

namespace animlod {

namespace {

// A cost per (point, frame) term below this fraction of the largest coordinate is rounding: each
// term is a distance between points that size, good to ~1e-16 of it.
constexpr double kRounding = 1e-12;
// Costs this close relative to each other are equal: rounding of sums of many such terms.
constexpr double kTie = 1e-9;

// c = a b for row-major 4 x 4 matrices.
void multiply(const double* a, const double* b, double* c) {
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double sum = 0.0;
      for (int k = 0; k < 4; ++k) sum += a[4 * i + k] * b[4 * k + j];
      c[4 * i + j] = sum;
    }
}

// The inverse of a rigid transform: rotation transposed, translation -R^T t.
void rigid_inverse(const double* m, double* inverse) {
  for (int i = 0; i < 3; ++i) {
    double sum = 0.0;
    for (int k = 0; k < 3; ++k) {
      inverse[4 * i + k] = m[4 * k + i];
      sum += m[4 * k + i] * m[4 * k + 3];
    }
    inverse[4 * i + 3] = -sum;
  }
  inverse[12] = inverse[13] = inverse[14] = 0.0;
  inverse[15] = 1.0;
}

// |m p - q| for a rigid transform m (row-major 4 x 4) and points p, q.
double moved_distance(const double* m, const double* p, const double* q) {
  double squared = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double moved = m[4 * i] * p[0] + m[4 * i + 1] * p[1] + m[4 * i + 2] * p[2] + m[4 * i + 3];
    squared += (moved - q[i]) * (moved - q[i]);
  }
  return std::sqrt(squared);
}

double distance(const double* p, const double* q) {
  const double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

class GreedyFreezes {
 public:
  GreedyFreezes(const double* world, const double* key_local, const int32_t* parents, size_t frames, size_t joints)
      : key_local_(key_local), parents_(parents), n_(frames), j_(joints), world_(world, world + 16 * frames * joints),
        original_(3 * frames * joints), error_(frames * joints, 0.0), below_(joints * joints, 0), moves_(16 * frames) {
    for (size_t f = 0; f < n_; ++f)
      for (size_t p = 0; p < j_; ++p)
        for (int a = 0; a < 3; ++a) {
          original_[3 * (f * j_ + p) + a] = transform(f, p)[4 * a + 3];
          magnitude_ = std::max(magnitude_, std::abs(original_[3 * (f * j_ + p) + a]));
        }
    for (size_t joint = j_; joint-- > 0;) {  // children after parents: each subtree is complete below it
      below_[joint * j_ + joint] = 1;
      if (parents_[joint] < 0) continue;
      const auto parent = static_cast<size_t>(parents_[joint]);
      for (size_t d = joint; d < j_; ++d) below_[parent * j_ + d] |= below_[joint * j_ + d];
    }
  }

  bool in_subtree(size_t joint, size_t point) const { return below_[joint * j_ + point] != 0; }

  // How much freezing `joint` now would add to the summed distance of the points from their
  // original positions, over its subtree and the frames; 0 within rounding of the positions'
  // magnitude, so that joints which do not move tie (and go by index) whatever the order of the
  // sums: a still end joint's cost is ~1e-12 of the figure, noise that once decided the order.
  double cost(size_t joint) {
    compute_moves(joint);
    double total = 0.0;
    size_t terms = 0;
    for (size_t p = joint; p < j_; ++p) {
      if (!in_subtree(joint, p)) continue;
      double growth = 0.0;
      for (size_t f = 0; f < n_; ++f)
        growth += moved_distance(&moves_[16 * f], position(f, p).data(), &original_[3 * (f * j_ + p)]) - error_[f * j_ + p];
      total += growth;
      terms += n_;
    }
    return std::abs(total) <= kRounding * magnitude_ * static_cast<double>(terms) ? 0.0 : total;
  }

  // Freezes `joint`: its subtree moves by its freeze's rigid transform in every frame.
  void freeze(size_t joint) {
    compute_moves(joint);
    double moved[16];
    for (size_t f = 0; f < n_; ++f)
      for (size_t p = joint; p < j_; ++p) {
        if (!in_subtree(joint, p)) continue;
        double* m = transform(f, p);
        multiply(&moves_[16 * f], m, moved);
        std::copy(moved, moved + 16, m);
        error_[f * j_ + p] = distance(position(f, p).data(), &original_[3 * (f * j_ + p)]);
      }
  }

 private:
  double* transform(size_t f, size_t p) { return &world_[16 * (f * j_ + p)]; }
  std::array<double, 3> position(size_t f, size_t p) {
    const double* m = transform(f, p);
    return {m[3], m[7], m[11]};
  }

  // moves_ (n, 4, 4): the parent's world transform x the key local transform x the inverse of the
  // joint's current world transform, per frame.
  void compute_moves(size_t joint) {
    const auto parent = static_cast<size_t>(parents_[joint]);
    double frozen[16], inverse[16];
    for (size_t f = 0; f < n_; ++f) {
      multiply(transform(f, parent), key_local_ + 16 * joint, frozen);
      rigid_inverse(transform(f, joint), inverse);
      multiply(frozen, inverse, &moves_[16 * f]);
    }
  }

  const double* key_local_;
  const int32_t* parents_;
  size_t n_, j_;
  double magnitude_ = 0.0;  // the largest coordinate of a point: what rounding is relative to
  std::vector<double> world_, original_, error_;  // (n, J, 16), (n, J, 3), (n, J)
  std::vector<uint8_t> below_;                    // (J, J): [j, d] for d = j or below it
  std::vector<double> moves_;
};

}  // namespace

Status cumulative_freeze_steps(const double* world, const double* key_local, const int32_t* parents,
                               const uint8_t* candidates, size_t frame_count, size_t joint_count, double* scores) {
  if (Status status = validate_parents(parents, joint_count); !status.ok) return status;
  for (size_t j = 0; j < joint_count; ++j)
    if (parents[j] < 0 && candidates[j])
      return Status::error("candidates[" + std::to_string(j) + "]: the root cannot freeze");
  for (size_t i = 0; i < 16 * frame_count * joint_count; ++i)
    if (!std::isfinite(world[i]))
      return Status::error("world[" + std::to_string(i / 16 / joint_count) + ", " +
                           std::to_string(i / 16 % joint_count) + "]: not a finite transform");
  for (size_t i = 0; i < 16 * joint_count; ++i)
    if (!std::isfinite(key_local[i]))
      return Status::error("key_local[" + std::to_string(i / 16) + "]: not a finite transform");

  constexpr double kNever = std::numeric_limits<double>::infinity();
  std::fill(scores, scores + joint_count, kNever);
  GreedyFreezes figure(world, key_local, parents, frame_count, joint_count);
  std::vector<double> cost(joint_count, kNever);
  std::vector<uint8_t> stale(candidates, candidates + joint_count);
  size_t steps = 0;
  for (size_t j = 0; j < joint_count; ++j) steps += candidates[j] ? 1 : 0;
  for (size_t step = 0; step < steps; ++step) {
    for (size_t j = 0; j < joint_count; ++j) {
      if (!stale[j]) continue;
      cost[j] = figure.cost(j);
      if (!std::isfinite(cost[j]))
        return Status::error("world: the distances of joint " + std::to_string(j) +
                             "'s subtree overflow (coordinates beyond double range)");
    }
    // Ties, costs within kTie of the lowest (a symmetric figure's left and right joints), go to
    // the lowest index, whatever the rounding of the sums.
    const double lowest = *std::min_element(cost.begin(), cost.end());
    size_t chosen = 0;
    while (!(cost[chosen] <= lowest + kTie * std::abs(lowest))) ++chosen;
    scores[chosen] = static_cast<double>(step);
    cost[chosen] = kNever;
    figure.freeze(chosen);
    // Only the costs of the frozen joint's descendants and ancestors change.
    for (size_t j = 0; j < joint_count; ++j)
      stale[j] = (figure.in_subtree(chosen, j) || figure.in_subtree(j, chosen)) && candidates[j] &&
                 std::isfinite(cost[j]);
  }
  return Status::success();
}

}  // namespace animlod
