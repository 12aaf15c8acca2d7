// The inner minimisation of the re-fit's free points (see the header); seeds/000, Eqs. 5, 6 and 8:
// per cluster, alpha |x - x^o|^2 / L^2 over its points plus gamma (cos theta - cos theta_0)^2
// over the angle triples that touch it, minimised by Newton's method with a backtracking line
// search. The exact Hessian is used where it is positive definite (quadratic convergence at
// the minimum); elsewhere (an angle term can be concave) it is shifted by a multiple of the
// identity until it is, so every step descends.
#include "motion_refit_free_points.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "motion_refit_detail.hpp"
#include "union_find.hpp"

namespace animlod::detail {

namespace {

// Newton iterations per cluster and evaluation; from set_start's minimum a few steps usually do.
constexpr int kMaxIterations = 50;
constexpr int kMaxHalvings = 40;
// A step shorter than this fraction of L, or a Newton decrement below this fraction of the
// value, ends the iteration: at quadratic convergence the gradient left is then far below what
// SLSQP's stopping rule can see.
constexpr double kStepTolerance = 1e-13;
constexpr double kDecrementTolerance = 1e-15;

}  // namespace

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
  for (const Cluster& cluster : clusters_) largest = std::max(largest, 3 * cluster.points.size());
  gradient_.resize(largest);
  hessian_.resize(largest * largest);
  step_.resize(largest);
  trial_.resize(largest);
}

double FreePointClusters::cluster_energy(const Cluster& cluster, const double* x, const double* original,
                                         double* gradient, double* hessian) {
  const size_t n = 3 * cluster.points.size();
  const double wd = problem_.distance_weight / (problem_.length_scale * problem_.length_scale);
  double value = 0.0;
  if (gradient) std::fill(gradient, gradient + n, 0.0);
  if (hessian) std::fill(hessian, hessian + n * n, 0.0);
  for (size_t i = 0; i < cluster.points.size(); ++i)  // Ed
    for (int a = 0; a < 3; ++a) {
      const double delta = x[3 * cluster.points[i] + a] - original[3 * cluster.points[i] + a];
      value += wd * delta * delta;
      if (gradient) gradient[3 * i + a] = 2.0 * wd * delta;
      if (hessian) hessian[(3 * i + a) * n + 3 * i + a] = 2.0 * wd;
    }
  double term_gradient[9], term_hessian[81];
  for (int32_t k : cluster.triples) {  // Ea
    value += angle_term(problem_, x, static_cast<size_t>(k), false, gradient ? term_gradient : nullptr,
                        hessian ? term_hessian : nullptr);
    if (!gradient) continue;
    const int32_t* triple = problem_.angle_triples + 3 * k;
    for (int pi = 0; pi < 3; ++pi) {
      const int32_t li = local_[triple[pi]];
      if (li < 0) continue;  // a held point of the triple
      for (int a = 0; a < 3; ++a) gradient[3 * li + a] += term_gradient[3 * pi + a];
      if (!hessian) continue;
      for (int pj = 0; pj < 3; ++pj) {
        const int32_t lj = local_[triple[pj]];
        if (lj < 0) continue;
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            hessian[(3 * li + a) * n + 3 * lj + b] += term_hessian[9 * (3 * pi + a) + 3 * pj + b];
      }
    }
  }
  return value;
}

void FreePointClusters::set_start(const double* x, const double* original) {
  start_.assign(x, x + 3 * problem_.point_count);
  // Clusters share no point and no triple, so one copy serves every cluster's second start.
  best_.assign(start_.begin(), start_.end());
  for (const Cluster& cluster : clusters_) {
    // The minima reached from x and from the original positions (Ed's minimum), the lower one:
    // the angle terms have several minima.
    const double from_start = newton(cluster, start_.data(), original);
    for (int32_t point : cluster.points) std::copy_n(original + 3 * point, 3, best_.begin() + 3 * point);
    if (newton(cluster, best_.data(), original) < from_start)
      for (int32_t point : cluster.points) std::copy_n(best_.begin() + 3 * point, 3, start_.begin() + 3 * point);
  }
}

void FreePointClusters::minimise(double* x, const double* original) {
  for (const Cluster& cluster : clusters_) {
    for (int32_t point : cluster.points) std::copy_n(start_.begin() + 3 * point, 3, x + 3 * point);
    newton(cluster, x, original);
  }
}

double FreePointClusters::newton(const Cluster& cluster, double* x, const double* original) {
  const double tolerance = kStepTolerance * problem_.length_scale;
  const double curvature = 2.0 * problem_.distance_weight / (problem_.length_scale * problem_.length_scale);
  const auto n = static_cast<Eigen::Index>(3 * cluster.points.size());
  Eigen::Map<Eigen::VectorXd> gradient(gradient_.data(), n), step(step_.data(), n), saved(trial_.data(), n);
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> hessian(hessian_.data(), n, n);
  double value = 0.0;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    value = cluster_energy(cluster, x, original, gradient_.data(), hessian_.data());
    // Where an angle term makes the Hessian indefinite, shift it towards Ed's curvature until
    // it is positive definite (Levenberg): every step then descends.
    Eigen::LLT<Eigen::MatrixXd> llt(hessian);
    for (double shift = curvature; llt.info() != Eigen::Success && std::isfinite(shift); shift *= 4.0)
      llt.compute(Eigen::MatrixXd(hessian) + shift * Eigen::MatrixXd::Identity(n, n));
    if (llt.info() != Eigen::Success) break;  // not finite: nothing to step along
    step = -llt.solve(gradient);
    // -slope, the Newton decrement, is about twice the value left to gain: stop when that is
    // below what rounding resolves.
    const double slope = gradient.dot(step);
    if (!(slope < -kDecrementTolerance * value)) break;
    for (Eigen::Index i = 0; i < n; ++i) saved[i] = x[3 * cluster.points[i / 3] + i % 3];
    double t = 1.0;
    int halvings = 0;
    double trial = value;
    for (;;) {
      for (Eigen::Index i = 0; i < n; ++i) x[3 * cluster.points[i / 3] + i % 3] = saved[i] + t * step[i];
      trial = cluster_energy(cluster, x, original, nullptr, nullptr);
      if (trial <= value + 1e-4 * t * slope) break;
      if (++halvings == kMaxHalvings) break;
      t *= 0.5;
    }
    if (halvings == kMaxHalvings) {  // no decrease along a descent direction: rounding
      for (Eigen::Index i = 0; i < n; ++i) x[3 * cluster.points[i / 3] + i % 3] = saved[i];
      break;
    }
    value = trial;
    if (t * step.cwiseAbs().maxCoeff() <= tolerance) break;
  }
  return value;
}

}  // namespace animlod::detail
