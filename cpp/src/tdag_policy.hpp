// The TDAG's cost-and-placement policy of the collapse engine (collapse_engine.hpp): quadric
// half-edge collapses of one frame [5], with the online construction's history term
// (Shamir and Pascucci 2001, Section 2 and [17]) as an optional addition to the priority.
#pragma once

#include <cstdint>
#include <vector>

#include "collapse_engine.hpp"
#include "quadric.hpp"
#include "tdag_hierarchy.hpp"

namespace animlod::detail {

// The history term of the online construction: collapses of the previous frame's hierarchy
// come first, in its order, when lambda is large. priority = cost + lambda * s * h with s the
// previous frame's mean collapse cost and h the collapse's rank there divided by its collapse
// count (2 for a collapse the previous frame does not have).
class HistoryTerm {
 public:
  HistoryTerm(const CollapseTable& table, const FrameHierarchy& previous, const std::vector<double>& previous_costs,
              double lambda);
  double priority(int32_t kept_node, int32_t removed_node, double cost) const;

 private:
  const CollapseTable& table_;
  std::vector<int32_t> rank_;  // node -> index in the previous frame's order, -1: not there
  double count_ = 1.0;
  double weight_ = 0.0;        // lambda * s
};

// Half-edge collapses in the engine's one frame: the merged vertex takes the position of one
// endpoint (the one of lower priority; the kept one when it is locked), at the quadric cost of
// the merged quadric there plus kLengthWeight times the squared edge length. Quadric costs
// vanish on flat and cylindrical parts, where ties broken by index would grow one cluster
// along a line; the small length term takes the shorter edges first there, which keeps the
// hierarchy balanced and the displacement bounds small.
//
// The policy logs every collapse it is asked to merge (vertices, which position, quadric cost)
// and keeps the hierarchy node of every live vertex, so that the history term can name the
// node a candidate would make.
class TdagCollapsePolicy final : public CollapsePolicy {
 public:
  static constexpr double kLengthWeight = 1e-3;

  // `engine` must have one frame: the geometry being decimated.
  TdagCollapsePolicy(const CollapseEngine& engine, std::vector<Quadric> quadrics, CollapseTable& table,
                     const HistoryTerm* history);

  void evaluate(Candidate& candidate) override;
  void place(Candidate& candidate, std::vector<Eigen::Vector3d>& placed) override;
  void merge(const Candidate& candidate) override;

  const std::vector<VertexCollapse>& collapses() const { return collapses_; }
  const std::vector<double>& costs() const { return costs_; }  // quadric cost of each collapse

 private:
  const CollapseEngine& engine_;
  std::vector<Quadric> quadrics_;  // (P,) merged into the kept vertex
  CollapseTable& table_;
  const HistoryTerm* history_;
  std::vector<int32_t> node_of_;   // (P,) hierarchy node of each live vertex
  std::vector<VertexCollapse> collapses_;
  std::vector<double> costs_;
};

}  // namespace animlod::detail
