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
  // The other points of the cluster's angle triples (increasing): where E ties it to the rest.
  const std::vector<int32_t>& held_points(size_t cluster) const { return clusters_[cluster].held; }

  // Starts a frame's minimisations. The fixed start: of the minima over the free points reached
  // from x (P, 3) and from the original positions (Ed's minimum), with x's other points, the
  // lower one (the angle terms have several minima). Forgets the previous frame's minima.
  void set_start(const double* x, const double* original);

  // Moves the free points of x (P, 3) to a minimum of E over them with every other point held:
  // of Newton's method from the fixed start and from the cluster's latest minimum of this frame,
  // the lower one. The fixed start moves with the cluster's held points (by their mean
  // displacement since set_start), so that it starts near the new minimum: left where it was,
  // Newton took 1.8 times the iterations from it on Xbot's fingers. From the fixed start alone,
  // a step of the held points can carry Newton into another of the angle terms' minima, and E
  // jumps where it should vary smoothly: on Xbot's fingers, SLSQP then stalled at such a jump for
  // hundreds of evaluations. The latest minimum follows the valley SLSQP is in. Held points met
  // before in this frame get the minimum they got then, so E is a function of the variables
  // within a solve, and the point SLSQP returns (one it evaluated) is placed as it was when
  // evaluated. original: the one given to set_start.
  void minimise(double* x, const double* original);

 private:
  struct Cluster {
    std::vector<int32_t> points;   // free points, in increasing order
    std::vector<int32_t> triples;  // angle triples with at least one of them
    BlockCholesky hessian;         // over the points (in cluster order), coupled by the triples
    // This frame's minima: the held points of the triples (the other points of E's part that
    // depends on the cluster) where they were, and the minimum placed for them, oldest first.
    std::vector<int32_t> held;
    std::vector<double> held_at, minima;  // (entries, 3 held) and (entries, 3 points)
    int rung = 0;  // the last Levenberg shift's k (BlockCholesky::factor_least_shift)
  };
  // E's part that depends on the cluster's points at x, with its gradient (3 n) and exact
  // Hessian (into cluster.hessian) when asked.
  double cluster_energy(Cluster& cluster, const double* x, const double* original, double* gradient,
                        bool hessian);

  // Whether the held points of x (P, 3) are where they were for the cluster's minimum `entry`.
  bool held_where(const Cluster& cluster, size_t entry, const double* x) const;

  // Newton's method on one cluster from where x has its points; returns the cluster's E there.
  double newton(Cluster& cluster, double* x, const double* original);

  const MotionRefitProblem& problem_;
  std::vector<Cluster> clusters_;
  std::vector<int32_t> local_;  // (P,) a free point's index in its cluster, -1 otherwise
  std::vector<double> start_;   // (P, 3) set_start's positions (only free points are read)
  std::vector<double> gradient_, step_, trial_, best_, from_start_;
};

}  // namespace animlod::detail
