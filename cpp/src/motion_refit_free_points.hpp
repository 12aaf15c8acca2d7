// Points of a re-fit frame that SLSQP does not need to see (motion_refit_free_points.cpp).
//
// At coarse levels most points are frozen joints and the end sites below them: no held length,
// coincident pair or handed group touches them, only Ed (Eq. 6) and the angles of Ea (Eq. 8). E
// is smooth in them and has no constraint on them, so for given positions of the other points
// their optimum is an unconstrained minimum, found here by Newton's method, cluster by cluster
// (points linked by angle triples). SLSQP then works on the other points only, whose count sets
// its cost (cubic), and no longer crawls along the curved valleys that the angle terms of short
// frozen bones make. At the inner minimum dE/dx_free = 0, so E's gradient over the other points
// is the same with or without the inner solve (the envelope theorem), and the minima of the
// reduced problem are those of the full one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "animlod/motion_refit.hpp"
#include "motion_refit_block_cholesky.hpp"

namespace animlod::detail {

class FreePointClusters {
 public:
  // free: (P,) 1 for the points to minimise here (never the root, never a point of a length,
  // coincident pair or handed group).
  FreePointClusters(const MotionRefitProblem& problem, const std::vector<uint8_t>& free);

  bool contains(size_t point) const { return local_[point] >= 0; }
  // Clusters share no term, so E's Hessian over the free points is block diagonal by cluster.
  size_t cluster_count() const { return clusters_.size(); }
  const std::vector<int32_t>& cluster_points(size_t cluster) const { return clusters_[cluster].points; }

  // Where every minimisation starts until the next call: of the minima over the free points
  // reached from x (P, 3) and from the original positions (Ed's minimum), with x's other points,
  // the lower one (the angle terms have several minima). A fixed start per frame makes the
  // minimum a function of the other points alone: starting from the last minimum instead would
  // let a far trial step of SLSQP carry the free points into another basin, and E would differ
  // at the same variables.
  void set_start(const double* x, const double* original);

  // Moves the free points of x (P, 3) to the minimum of E over them with every other point
  // held, reached from set_start's positions. original: the one given to set_start.
  void minimise(double* x, const double* original);

 private:
  struct Cluster {
    std::vector<int32_t> points;   // free points, in increasing order
    std::vector<int32_t> triples;  // angle triples with at least one of them
    BlockCholesky hessian;         // over the points (in cluster order), coupled by the triples
    // Newton from the same start with the same held points ends at the same minimum, so
    // minimise keeps its last one: the held points of the triples (the other points of E's part
    // that depends on the cluster), where they were, and the minimum; until set_start.
    std::vector<int32_t> held;
    std::vector<double> held_at, minimum;
    bool remembered = false;
  };
  // E's part that depends on the cluster's points at x, with its gradient (3 n) and exact
  // Hessian (into cluster.hessian) when asked.
  double cluster_energy(Cluster& cluster, const double* x, const double* original, double* gradient,
                        bool hessian);

  // Newton's method on one cluster from where x has its points; returns the cluster's E there.
  double newton(Cluster& cluster, double* x, const double* original);

  const MotionRefitProblem& problem_;
  std::vector<Cluster> clusters_;
  std::vector<int32_t> local_;  // (P,) a free point's index in its cluster, -1 otherwise
  std::vector<double> start_;   // (P, 3) set_start's positions (only free points are read)
  std::vector<double> gradient_, step_, trial_, best_;
};

}  // namespace animlod::detail
