// The TDAG's policy of the collapse engine: quadric half-edge collapses of one frame and the
// online construction's history term (Shamir and Pascucci 2001, Section 2: "an enhanced
// priority function ... introducing some history considerations which augment the regular
// priorities of decimation cost ... A weighted sum of the two components is used").
#include "tdag_policy.hpp"

#include <algorithm>

namespace animlod::detail {

HistoryTerm::HistoryTerm(const CollapseTable& table, const FrameHierarchy& previous,
                         const std::vector<double>& previous_costs, double lambda)
    : table_(table) {
  rank_.assign(table.representative.size(), -1);
  double total = 0.0;
  for (size_t i = 0; i < previous.nodes.size(); ++i) {
    rank_[static_cast<size_t>(previous.nodes[i])] = static_cast<int32_t>(i);
    total += previous_costs[i];
  }
  count_ = std::max<double>(1.0, static_cast<double>(previous.nodes.size()));
  const double mean = previous.nodes.empty() ? 0.0 : total / static_cast<double>(previous.nodes.size());
  weight_ = lambda * (mean > 0.0 ? mean : 1.0);
}

double HistoryTerm::priority(int32_t kept_node, int32_t removed_node, double cost) const {
  if (weight_ == 0.0) return cost;
  const int32_t node = table_.find(kept_node, removed_node);
  const int32_t rank = node >= 0 && static_cast<size_t>(node) < rank_.size() ? rank_[static_cast<size_t>(node)] : -1;
  const double h = rank >= 0 ? static_cast<double>(rank) / count_ : 2.0;
  return cost + weight_ * h;
}

TdagCollapsePolicy::TdagCollapsePolicy(const CollapseEngine& engine, std::vector<Quadric> quadrics,
                                       CollapseTable& table, const HistoryTerm* history)
    : engine_(engine), quadrics_(std::move(quadrics)), table_(table), history_(history) {
  node_of_.resize(engine.point_count());
  for (size_t p = 0; p < node_of_.size(); ++p) node_of_[p] = static_cast<int32_t>(p);
}

void TdagCollapsePolicy::evaluate(Candidate& candidate) {
  const Eigen::Vector3d kept = engine_.position(candidate.kept, 0), removed = engine_.position(candidate.removed, 0);
  const Quadric merged = quadrics_[static_cast<size_t>(candidate.kept)] + quadrics_[static_cast<size_t>(candidate.removed)];
  const double length = kLengthWeight * (kept - removed).squaredNorm();
  const double cost_kept = merged.evaluate(kept), cost_removed = merged.evaluate(removed);
  const int32_t kept_node = node_of_[static_cast<size_t>(candidate.kept)];
  const int32_t removed_node = node_of_[static_cast<size_t>(candidate.removed)];
  double priority_kept = cost_kept + length, priority_removed = cost_removed + length;
  if (history_) {
    priority_kept = history_->priority(kept_node, removed_node, priority_kept);
    priority_removed = history_->priority(removed_node, kept_node, priority_removed);
  }
  // A locked vertex never moves: the merged vertex stays where it is.
  const bool from_removed = !engine_.locked(candidate.kept) && priority_removed < priority_kept;
  candidate.t = from_removed ? 1.0 : 0.0;
  candidate.cost = from_removed ? priority_removed : priority_kept;
  candidate.error = from_removed ? cost_removed : cost_kept;
}

void TdagCollapsePolicy::place(Candidate& candidate, std::vector<Eigen::Vector3d>& placed) {
  placed[0] = engine_.position(candidate.t > 0.5 ? candidate.removed : candidate.kept, 0);
}

void TdagCollapsePolicy::merge(const Candidate& candidate) {
  const auto kept = static_cast<size_t>(candidate.kept), removed = static_cast<size_t>(candidate.removed);
  const bool from_removed = candidate.t > 0.5;
  quadrics_[kept] += quadrics_[removed];
  node_of_[kept] = from_removed ? table_.add(node_of_[removed], node_of_[kept]) : table_.add(node_of_[kept], node_of_[removed]);
  collapses_.push_back({candidate.removed, candidate.kept, from_removed});
  costs_.push_back(candidate.error);
}

}  // namespace animlod::detail
