// Pendant trees of the motion re-fit (see the header); seeds/000, Eqs. 5-7 under hard
// constraints. A tree point k sits at x_parent + b_k u_k with |u_k| = 1, so its held length
// holds exactly and only Ed (Eq. 6) is left: sum_i |x_i - x^o_i|^2 over the tree (alpha / L^2 is
// a common factor). Newton's method on the bone directions: each step moves u_k in its tangent
// plane (two coordinates s_k) and renormalises. With r_i = x_i - x^o_i and R_k the sum of r over
// k's subtree, the gradient is 2 b_k e_kc . R_k, and the Hessian 2 b_k b_l m_kl (e_kc . e_ld),
// m_kl the size of the deeper subtree when one of k, l lies below the other (0 otherwise), minus
// 2 b_k (u_k . R_k) on k's diagonal (the sphere's curvature). Where that Hessian is not positive
// definite it is shifted by a multiple of the identity; a backtracking line search makes every
// step descend.
#include "motion_refit_pendant_trees.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "motion_refit_detail.hpp"

namespace animlod::detail {

namespace {

struct Vec3 {
  double v[3];
  double& operator[](int i) { return v[i]; }
  double operator[](int i) const { return v[i]; }
};

double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

Vec3 point(const double* x, int32_t k) { return {{x[3 * k], x[3 * k + 1], x[3 * k + 2]}}; }

// (a unit vector, true) along d, or (along fallback, false) when d has no length.
bool normalised(Vec3& d) {
  const double norm = std::sqrt(dot(d, d));
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  for (int a = 0; a < 3; ++a) d[a] /= norm;
  return true;
}

}  // namespace

PendantTrees::PendantTrees(const MotionRefitProblem& problem, bool enabled)
    : anchor_of_(problem.point_count, -1), inner_pairs_(problem.length_pair_count, 0), jacobians_(problem.point_count) {
  if (!enabled) return;
  const size_t p = problem.point_count;
  std::vector<uint8_t> other(p, 0);  // in a term other than Ed and held lengths (or the root)
  set_points_of(problem.coincident_pairs, problem.coincident_pair_count, 2, 1, other);
  set_points_of(problem.angle_triples, problem.angle_triple_count, 3, 1, other);
  set_points_of(problem.handed_quads, problem.handed_quad_count, 4, 1, other);
  set_points_of(problem.flat_quads, problem.flat_quad_count, 4, 1, other);
  other[0] = 1;
  std::vector<std::vector<std::pair<int32_t, int32_t>>> links(p);  // (neighbour, pair)
  for (size_t k = 0; k < problem.length_pair_count; ++k) {
    const int32_t a = problem.length_pairs[2 * k], b = problem.length_pairs[2 * k + 1];
    links[a].push_back({b, static_cast<int32_t>(k)});
    links[b].push_back({a, static_cast<int32_t>(k)});
  }

  // Peel from the tips: a point whose lengths all lead to peeled points but one hangs from it.
  std::vector<int32_t> parent(p, -1), parent_pair(p, -1), open(p, 0), order;
  std::vector<uint8_t> peeled(p, 0);
  for (size_t k = 0; k < p; ++k) open[k] = static_cast<int32_t>(links[k].size());
  std::vector<int32_t> queue;
  for (size_t k = 0; k < p; ++k)
    if (!other[k] && open[k] == 1) queue.push_back(static_cast<int32_t>(k));
  while (!queue.empty()) {
    const int32_t k = queue.back();
    queue.pop_back();
    if (peeled[k] || open[k] != 1) continue;
    for (const auto& [neighbour, pair] : links[k]) {
      if (peeled[neighbour]) continue;
      peeled[k] = 1;
      parent[k] = neighbour, parent_pair[k] = pair;
      order.push_back(k);
      if (--open[neighbour] == 1 && !other[neighbour] && !peeled[neighbour]) queue.push_back(neighbour);
      break;
    }
  }

  // One tree per peeled point hanging directly from an unpeeled one, its points parents first
  // (peeling went tips first, so the reverse of `order` has every parent before its children).
  std::vector<int32_t> tree_of(p, -1), local(p, -1);
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    const int32_t k = *it;
    const int32_t up = parent[k];
    if (!peeled[up]) {
      tree_of[k] = static_cast<int32_t>(trees_.size());
      trees_.emplace_back();
      trees_.back().anchor = up;
    } else {
      tree_of[k] = tree_of[up];
    }
    Tree& tree = trees_[tree_of[k]];
    local[k] = static_cast<int32_t>(tree.points.size());
    tree.points.push_back(k);
    tree.parent.push_back(peeled[up] ? local[up] : -1);
    tree.length.push_back(problem.key_lengths[parent_pair[k]]);
  }
  // One-point trees are the leaves motion_refit_reduction solves in closed form.
  trees_.erase(std::remove_if(trees_.begin(), trees_.end(), [](const Tree& t) { return t.points.size() < 2; }),
               trees_.end());
  for (Tree& tree : trees_) {
    const size_t n = tree.points.size();
    tree.below.assign(n * n, 0);
    tree.size.assign(n, 0);
    for (size_t i = 0; i < n; ++i)
      for (int32_t k = static_cast<int32_t>(i); k >= 0; k = tree.parent[k]) {
        tree.below[k * n + i] = 1;
        ++tree.size[k];
      }
    for (int32_t k : tree.points) {
      anchor_of_[k] = tree.anchor;
      inner_pairs_[parent_pair[k]] = 1;
    }
  }
}

void PendantTrees::place(double* x, const double* original) {
  for (const Tree& tree : trees_) place_tree(tree, x, original);
}

void PendantTrees::place_tree(const Tree& tree, double* x, const double* original) {
  const size_t n = tree.points.size();
  std::vector<Vec3> u(n), e1(n), e2(n), sums(n), at(n), trial_u(n);
  // Positions of the tree for bone directions `directions` into `out`; the value sum |x - x^o|^2.
  auto positions = [&](const std::vector<Vec3>& directions, std::vector<Vec3>& out) {
    double value = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const Vec3 base = tree.parent[i] < 0 ? point(x, tree.anchor) : out[tree.parent[i]];
      const Vec3 target = point(original, tree.points[i]);
      for (int a = 0; a < 3; ++a) {
        out[i][a] = base[a] + tree.length[i] * directions[i][a];
        const double d = out[i][a] - target[a];
        value += d * d;
      }
    }
    return value;
  };
  const auto m = static_cast<Eigen::Index>(2 * n);
  Eigen::VectorXd gradient(m), step(m);
  Eigen::MatrixXd hessian(m, m);
  // Gradient and Hessian over the tangent coordinates at u (positions `at`).
  auto assemble = [&]() {
    for (size_t i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a) sums[i][a] = at[i][a] - original[3 * tree.points[i] + a];
      tangent_basis(u[i].v, e1[i].v, e2[i].v);
    }
    for (size_t i = n; i-- > 0;)  // children after parents: subtree sums accumulate upwards
      if (tree.parent[i] >= 0)
        for (int a = 0; a < 3; ++a) sums[tree.parent[i]][a] += sums[i][a];
    for (size_t k = 0; k < n; ++k) {
      const Vec3* ek[2] = {&e1[k], &e2[k]};
      for (int c = 0; c < 2; ++c) {
        gradient(2 * k + c) = 2.0 * tree.length[k] * dot(*ek[c], sums[k]);
        for (size_t l = 0; l < n; ++l) {
          const int32_t shared = tree.below[k * n + l] ? tree.size[l] : (tree.below[l * n + k] ? tree.size[k] : 0);
          const Vec3* el[2] = {&e1[l], &e2[l]};
          for (int d = 0; d < 2; ++d)
            hessian(2 * k + c, 2 * l + d) = 2.0 * tree.length[k] * tree.length[l] * shared * dot(*ek[c], *el[d]);
        }
        hessian(2 * k + c, 2 * k + c) -= 2.0 * tree.length[k] * dot(u[k], sums[k]);
      }
    }
  };
  // Factors the Hessian shifted by the smallest multiple of the identity (0, then growing) that
  // makes it positive definite; false when none does (a non-finite Hessian).
  Eigen::LLT<Eigen::MatrixXd> llt(m);
  auto factor = [&]() {
    const double scale = hessian.diagonal().cwiseAbs().maxCoeff();
    for (double shift = 0.0; std::isfinite(shift); shift = shift == 0.0 ? 1e-8 * scale + 1e-300 : 10.0 * shift) {
      llt.compute(hessian + shift * Eigen::MatrixXd::Identity(m, m));
      if (llt.info() == Eigen::Success) return true;
    }
    return false;
  };

  // Start: each bone aimed at its point's original position from its placed parent.
  for (size_t i = 0; i < n; ++i) {
    const int32_t k = tree.points[i];
    const int32_t up = tree.parent[i] < 0 ? tree.anchor : tree.points[tree.parent[i]];
    const Vec3 base = tree.parent[i] < 0 ? point(x, tree.anchor) : at[tree.parent[i]];
    Vec3 d{{original[3 * k] - base[0], original[3 * k + 1] - base[1], original[3 * k + 2] - base[2]}};
    if (!normalised(d)) {  // on the original position: along the original bone
      d = {{original[3 * k] - original[3 * up], original[3 * k + 1] - original[3 * up + 1],
            original[3 * k + 2] - original[3 * up + 2]}};
      if (!normalised(d)) d = {{1.0, 0.0, 0.0}};
    }
    u[i] = d;
    for (int a = 0; a < 3; ++a) at[i][a] = base[a] + tree.length[i] * d[a];
  }
  double value = positions(u, at);
  for (int iteration = 0; iteration < kNewtonIterations; ++iteration) {
    assemble();
    if (gradient.squaredNorm() == 0.0 || !factor()) break;
    step = -llt.solve(gradient);
    const double decrease = -gradient.dot(step);
    if (!(decrease > kNewtonDecrement * value)) break;
    double t = 1.0, trial_value = value;
    for (int halving = 0; halving < kNewtonHalvings; ++halving, t *= 0.5) {
      for (size_t k = 0; k < n; ++k) {
        for (int a = 0; a < 3; ++a) trial_u[k][a] = u[k][a] + t * (step(2 * k) * e1[k][a] + step(2 * k + 1) * e2[k][a]);
        normalised(trial_u[k]);
      }
      trial_value = positions(trial_u, sums);  // sums as scratch for the trial positions
      if (trial_value <= value - 1e-4 * t * decrease) break;
    }
    if (!(trial_value < value)) break;  // no descent left at rounding level
    u.swap(trial_u);
    value = positions(u, at);
    if (t * step.cwiseAbs().maxCoeff() < kNewtonStep) break;
  }

  // How the minimum follows the anchor (implicit function theorem): the gradient's derivative
  // with respect to the anchor is 2 b_k |subtree k| e_kc, so ds/da = -H^-1 of that, and
  // dx_i/da = I + sum over i's bones k of b_k (e_k1, e_k2) ds_k/da.
  // Without a factor (non-finite positions) the tree moves with its anchor unturned.
  assemble();
  Eigen::MatrixXd along(m, 3);
  for (size_t k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) {
      along(2 * k, a) = 2.0 * tree.length[k] * tree.size[k] * e1[k][a];
      along(2 * k + 1, a) = 2.0 * tree.length[k] * tree.size[k] * e2[k][a];
    }
  const Eigen::MatrixXd follow = factor() ? Eigen::MatrixXd(-llt.solve(along)) : Eigen::MatrixXd::Zero(m, 3);
  for (size_t i = 0; i < n; ++i) {
    const int32_t k = tree.points[i];
    for (int a = 0; a < 3; ++a) x[3 * k + a] = at[i][a];
    Matrix3& j = jacobians_[k];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) j[3 * a + b] = a == b ? 1.0 : 0.0;
    for (int32_t bone = static_cast<int32_t>(i); bone >= 0; bone = tree.parent[bone])
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          j[3 * a + b] +=
              tree.length[bone] * (e1[bone][a] * follow(2 * bone, b) + e2[bone][a] * follow(2 * bone + 1, b));
  }
}

}  // namespace animlod::detail
