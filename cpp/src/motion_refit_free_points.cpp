// The inner minimisation of the re-fit's free points (see the header); seeds/000, Eqs. 5, 6 and 8:
// per cluster, alpha |x - x^o|^2 / L^2 over its points plus gamma (cos theta - cos theta_0)^2
// over the angle triples that touch it, minimised by Newton's method with a backtracking line
// search. The exact Hessian is used where it is positive definite (quadratic convergence at
// the minimum); elsewhere (an angle term can be concave) it is shifted by a multiple of the
// identity until it is, so every step descends. The Hessian is sparse (a triple couples a point
// with its parent, grandparent, children and grandchildren only) and is factorised as such
// (motion_refit_block_cholesky.hpp): linear in the cluster's size, not cubic.
#include "motion_refit_free_points.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "motion_refit_detail.hpp"
#include "union_find.hpp"

namespace animlod::detail {

FreePointClusters::FreePointClusters(const MotionRefitProblem& problem, const std::vector<uint8_t>& free)
    : problem_(problem), local_(problem.point_count, -1), start_(3 * problem.point_count, 0.0) {
  const size_t p = problem.point_count;
  UnionFind sets(p);
  for (size_t k = 0; k < problem.angle_triple_count; ++k) {  // free points of one triple: one cluster
    int32_t first = -1;
    for (int c = 0; c < 3; ++c) {
      const int32_t point = problem.angle_triples[3 * k + c];
      if (!free[point]) continue;
      if (first < 0) first = point;
      else sets.unite(first, point);
    }
  }
  std::vector<int32_t> cluster_of(p, -1);
  for (size_t k = 0; k < p; ++k) {
    if (!free[k]) continue;
    const int32_t r = sets.find(static_cast<int32_t>(k));
    if (cluster_of[r] < 0) {
      cluster_of[r] = static_cast<int32_t>(clusters_.size());
      clusters_.emplace_back();
    }
    Cluster& cluster = clusters_[cluster_of[r]];
    local_[k] = static_cast<int32_t>(cluster.points.size());
    cluster.points.push_back(static_cast<int32_t>(k));
  }
  size_t largest = 0;
  for (size_t k = 0; k < problem.angle_triple_count; ++k) {
    int32_t cluster = -1;
    for (int c = 0; c < 3 && cluster < 0; ++c) {
      const int32_t point = problem.angle_triples[3 * k + c];
      if (free[point]) cluster = cluster_of[sets.find(point)];
    }
    if (cluster >= 0) clusters_[cluster].triples.push_back(static_cast<int32_t>(k));
  }
  for (Cluster& cluster : clusters_) {
    largest = std::max(largest, 3 * cluster.points.size());
    std::vector<std::pair<int32_t, int32_t>> coupled;  // free points of one triple
    for (int32_t k : cluster.triples)
      for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
          const int32_t la = local_[problem.angle_triples[3 * k + a]], lb = local_[problem.angle_triples[3 * k + b]];
          if (la >= 0 && lb >= 0) coupled.emplace_back(la, lb);
        }
    cluster.hessian = BlockCholesky(cluster.points.size(), coupled);
    for (int32_t k : cluster.triples)
      for (int c = 0; c < 3; ++c)
        if (!free[problem.angle_triples[3 * k + c]]) cluster.held.push_back(problem.angle_triples[3 * k + c]);
    std::sort(cluster.held.begin(), cluster.held.end());
    cluster.held.erase(std::unique(cluster.held.begin(), cluster.held.end()), cluster.held.end());
  }
  gradient_.resize(largest);
  step_.resize(largest);
  trial_.resize(largest);
  from_start_.resize(largest);
}

double FreePointClusters::cluster_energy(Cluster& cluster, const double* x, const double* original,
                                         double* gradient, bool hessian) {
  const size_t n = 3 * cluster.points.size();
  const double wd = problem_.distance_weight / (problem_.length_scale * problem_.length_scale);
  double value = 0.0;
  if (gradient) std::fill(gradient, gradient + n, 0.0);
  if (hessian) cluster.hessian.clear();
  const double ed_hessian[9] = {2.0 * wd, 0, 0, 0, 2.0 * wd, 0, 0, 0, 2.0 * wd};
  for (size_t i = 0; i < cluster.points.size(); ++i) {  // Ed
    for (int a = 0; a < 3; ++a) {
      const double delta = x[3 * cluster.points[i] + a] - original[3 * cluster.points[i] + a];
      value += wd * delta * delta;
      if (gradient) gradient[3 * i + a] = 2.0 * wd * delta;
    }
    if (hessian) cluster.hessian.add(static_cast<int32_t>(i), static_cast<int32_t>(i), ed_hessian);
  }
  double term_gradient[9], block[9];
  for (int32_t k : cluster.triples) {  // Ea
    const AngleTerm term(problem_, x, static_cast<size_t>(k), hessian);
    value += term.value();
    if (!gradient) continue;
    term.gradient(term_gradient);
    const int32_t* triple = problem_.angle_triples + 3 * k;
    for (int pi = 0; pi < 3; ++pi) {
      const int32_t li = local_[triple[pi]];
      if (li < 0) continue;  // a held point of the triple
      for (int a = 0; a < 3; ++a) gradient[3 * li + a] += term_gradient[3 * pi + a];
      if (!hessian) continue;
      for (int pj = pi; pj < 3; ++pj) {  // (li, lj) stands for (lj, li) too: the matrix is symmetric
        const int32_t lj = local_[triple[pj]];
        if (lj < 0) continue;
        term.hessian_block(pi, pj, block);
        cluster.hessian.add(li, lj, block);
      }
    }
  }
  return value;
}

void FreePointClusters::set_start(const double* x, const double* original) {
  start_.assign(x, x + 3 * problem_.point_count);
  // Clusters share no point and no triple, so one copy serves every cluster's second start.
  best_.assign(start_.begin(), start_.end());
  for (Cluster& cluster : clusters_) {
    cluster.held_at.clear();
    cluster.minima.clear();
    // The minima reached from x and from the original positions (Ed's minimum), the lower one:
    // the angle terms have several minima.
    const double from_start = newton(cluster, start_.data(), original);
    for (int32_t point : cluster.points) std::copy_n(original + 3 * point, 3, best_.begin() + 3 * point);
    if (newton(cluster, best_.data(), original) < from_start)
      for (int32_t point : cluster.points) std::copy_n(best_.begin() + 3 * point, 3, start_.begin() + 3 * point);
  }
}

bool FreePointClusters::held_where(const Cluster& cluster, size_t entry, const double* x) const {
  const double* at = cluster.held_at.data() + 3 * cluster.held.size() * entry;
  for (size_t i = 0; i < cluster.held.size(); ++i)
    if (!std::equal(at + 3 * i, at + 3 * i + 3, x + 3 * cluster.held[i])) return false;
  return true;
}

void FreePointClusters::minimise(double* x, const double* original) {
  for (Cluster& cluster : clusters_) {
    const size_t n = 3 * cluster.points.size(), met = cluster.minima.size() / n;
    auto place = [&](const double* minimum) {  // cluster order into x
      for (size_t i = 0; i < cluster.points.size(); ++i) std::copy_n(minimum + 3 * i, 3, x + 3 * cluster.points[i]);
    };
    size_t seen = met;  // the newest first: SLSQP returns to its latest points most
    while (seen > 0 && !held_where(cluster, seen - 1, x)) --seen;
    if (seen > 0) {
      place(cluster.minima.data() + (seen - 1) * n);
      continue;
    }
    double shift[3] = {0.0, 0.0, 0.0};  // the held points' mean move since set_start
    for (int32_t point : cluster.held)
      for (int a = 0; a < 3; ++a)
        shift[a] += (x[3 * point + a] - start_[3 * point + a]) / static_cast<double>(cluster.held.size());
    for (int32_t point : cluster.points)
      for (int a = 0; a < 3; ++a) x[3 * point + a] = start_[3 * point + a] + shift[a];
    const double from_start = newton(cluster, x, original);
    if (met > 0) {
      for (size_t i = 0; i < cluster.points.size(); ++i)
        std::copy_n(x + 3 * cluster.points[i], 3, from_start_.begin() + 3 * i);
      place(cluster.minima.data() + (met - 1) * n);
      if (newton(cluster, x, original) >= from_start) place(from_start_.data());
    }
    for (int32_t point : cluster.held) cluster.held_at.insert(cluster.held_at.end(), x + 3 * point, x + 3 * point + 3);
    for (int32_t point : cluster.points) cluster.minima.insert(cluster.minima.end(), x + 3 * point, x + 3 * point + 3);
  }
}

double FreePointClusters::newton(Cluster& cluster, double* x, const double* original) {
  const double tolerance = kNewtonStep * problem_.length_scale;
  const double curvature = 2.0 * problem_.distance_weight / (problem_.length_scale * problem_.length_scale);
  const size_t n = 3 * cluster.points.size();
  double* gradient = gradient_.data();
  double* step = step_.data();
  double* saved = trial_.data();
  double value = 0.0;
  double last_exact_step = 0.0;  // the previous step's length if it was a full, unshifted one
  for (int iteration = 0; iteration < kNewtonIterations; ++iteration) {
    value = cluster_energy(cluster, x, original, gradient, true);
    // Where an angle term makes the Hessian indefinite, shift it towards Ed's curvature until
    // it is positive definite (Levenberg): every step then descends.
    const bool exact = cluster.hessian.factor(0.0);
    if (!exact && !cluster.hessian.factor_least_shift(curvature, cluster.rung)) break;  // not finite: nothing to step along
    cluster.hessian.solve(gradient, step);
    // -slope, the Newton decrement, is about twice the value left to gain: stop when that is
    // below what rounding resolves.
    double slope = 0.0, largest = 0.0;
    for (size_t i = 0; i < n; ++i) {
      step[i] = -step[i];
      slope += gradient[i] * step[i];
      largest = std::max(largest, std::abs(step[i]));
    }
    if (!(slope < -kNewtonDecrement * value)) break;
    for (size_t i = 0; i < n; ++i) saved[i] = x[3 * cluster.points[i / 3] + i % 3];
    double t = 1.0;
    int halvings = 0;
    double trial = value;
    for (;;) {
      for (size_t i = 0; i < n; ++i) x[3 * cluster.points[i / 3] + i % 3] = saved[i] + t * step[i];
      trial = cluster_energy(cluster, x, original, nullptr, false);
      if (trial <= value + 1e-4 * t * slope) break;
      if (++halvings == kNewtonHalvings) break;
      t *= 0.5;
    }
    if (halvings == kNewtonHalvings) {  // no decrease along a descent direction: rounding
      for (size_t i = 0; i < n; ++i) x[3 * cluster.points[i / 3] + i % 3] = saved[i];
      break;
    }
    value = trial;
    const double length = t * largest;
    if (length <= tolerance) break;
    // Two full exact Newton steps in a row: convergence is quadratic, the next step about
    // length^2 (length / last^2); below the tolerance, it would only confirm this one.
    if (!exact || t < 1.0) {
      last_exact_step = 0.0;
    } else {
      if (length * length * length <= tolerance * last_exact_step * last_exact_step) break;
      last_exact_step = length;
    }
  }
  return value;
}

}  // namespace animlod::detail
