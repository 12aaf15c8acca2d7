// TDAG construction (Shamir and Pascucci 2001, Sections 3-4).
//
//   affine split     Section 3: A_t and the residual meshes (tdag_affine.cpp);
//   hierarchy        Section 4: one collapse order for all frames, governed by the first mesh,
//                    the average mesh, an arbitrary frame or AQEM over all frames; or online,
//                    every frame decimated with a priority that adds a history term favouring
//                    the order of the frame before (Section 2, [17]), so that where frames
//                    disagree the nodes and links get different time tags;
//   fields           per frame and collapse: the quadric cost c_{i,t} on the real frame
//                    (Section 4 stresses real meshes, not residuals; Figure 6's measure), and
//                    the error bound, made monotone along dependencies and stored as time-
//                    tagged runs (Section 2), so that a tolerance query always gives a valid cut.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "animlod/aqem.hpp"
#include "animlod/mesh_validation.hpp"
#include "animlod/tdag.hpp"
#include "tdag_data.hpp"
#include "tdag_decimate.hpp"

namespace animlod {

namespace {

using detail::CollapseTable;
using detail::FrameHierarchy;
using detail::Quadric;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Status check_options(const AnimatedMeshView& mesh, const TdagOptions& options) {
  if (options.governing == Governing::frame &&
      (options.governing_frame < 0 || static_cast<size_t>(options.governing_frame) >= mesh.frame_count))
    return Status::error("governing_frame: frame " + std::to_string(options.governing_frame) + " outside [0, " +
                         std::to_string(mesh.frame_count) + ")");
  if (!(std::isfinite(options.history_weight) && options.history_weight >= 0.0))
    return Status::error("history_weight: must be finite and >= 0, got " + std::to_string(options.history_weight));
  return Status::success();
}

// The online history term: collapses of the previous frame's hierarchy come first in its order
// when lambda is large.
class HistoryPriority final : public detail::CollapsePriority {
 public:
  HistoryPriority(const CollapseTable& table, const FrameHierarchy& previous, double lambda) : table_(table) {
    rank_.assign(table.representative.size(), -1);
    double total = 0.0;
    for (size_t i = 0; i < previous.nodes.size(); ++i) {
      rank_[static_cast<size_t>(previous.nodes[i])] = static_cast<int32_t>(i);
      total += previous.costs[i];
    }
    count_ = std::max<double>(1.0, static_cast<double>(previous.nodes.size()));
    const double mean = previous.nodes.empty() ? 0.0 : total / static_cast<double>(previous.nodes.size());
    weight_ = lambda * (mean > 0.0 ? mean : 1.0);
  }

  double priority(int32_t kept_node, int32_t removed_node, double cost) const override {
    if (weight_ == 0.0) return cost;
    const int32_t node = table_.find(kept_node, removed_node);
    const int32_t rank = node >= 0 && static_cast<size_t>(node) < rank_.size() ? rank_[static_cast<size_t>(node)] : -1;
    const double history = rank >= 0 ? static_cast<double>(rank) / count_ : 2.0;
    return cost + weight_ * history;
  }

 private:
  const CollapseTable& table_;
  std::vector<int32_t> rank_;  // node -> index in the previous frame's order, -1: not there
  double count_ = 1.0;
  double weight_ = 0.0;        // lambda * s
};

// Per-frame fields of the collapses, accumulated frame after frame.
class FieldBuilder {
 public:
  FieldBuilder(const AnimatedMeshView& mesh, const TdagOptions& options, double scale)
      : mesh_(mesh), scale_(scale) {
    if (options.boundary_quadrics) boundary_ = detail::boundary_sides(mesh.faces, mesh.face_count);
    use_boundary_ = options.boundary_quadrics;
  }

  // Adds frame t of hierarchy h (its collapses are already in `table`).
  void add_frame(int32_t t, const CollapseTable& table, const FrameHierarchy& h, TdagBuildReport& report);
  void finish(const CollapseTable& table, detail::TdagData& data);

 private:
  Eigen::Vector3d point(int32_t frame, int32_t vertex) const {
    const float* p = mesh_.frames + (static_cast<size_t>(frame) * mesh_.vertex_count + static_cast<size_t>(vertex)) * 3;
    return {p[0], p[1], p[2]};
  }
  void grow(size_t collapse_count, TdagBuildReport& report) {
    if (alive_.size() >= collapse_count) return;
    alive_.resize(collapse_count);
    links_.resize(collapse_count);
    errors_.resize(collapse_count);
    report.max_cost.resize(collapse_count, 0.0);
    report.use_counts.resize(collapse_count, 0);
  }

  const AnimatedMeshView& mesh_;
  double scale_;
  bool use_boundary_ = true;
  std::vector<detail::BoundarySide> boundary_;
  std::vector<TimeTag> alive_;                   // (C,)
  std::vector<TaggedSet<int32_t>> links_;        // (C,) dependencies
  std::vector<TaggedValue<uint16_t>> errors_;    // (C,) error codes
  std::vector<Quadric> quadrics_;                // (V + C,) scratch
  std::vector<double> bound_;                    // (V + C,) scratch: monotone bound in this frame
  std::vector<int32_t> stack_;
};

void FieldBuilder::add_frame(int32_t t, const CollapseTable& table, const FrameHierarchy& h,
                             TdagBuildReport& report) {
  const int32_t vertex_count = table.vertex_count();
  const size_t node_count = table.representative.size();
  grow(table.collapse_count(), report);
  report.collapse_counts.push_back(static_cast<int32_t>(h.nodes.size()));

  // Costs c_{i,t}: the quadric of a node is the sum of its cluster's vertex quadrics in frame t.
  const float* positions = mesh_.frames + static_cast<size_t>(t) * mesh_.vertex_count * 3;
  detail::vertex_quadrics(positions, mesh_.faces, mesh_.vertex_count, mesh_.face_count,
                          use_boundary_ ? &boundary_ : nullptr, quadrics_);
  quadrics_.resize(node_count);
  bound_.assign(node_count, 0.0);
  for (size_t i = 0; i < h.nodes.size(); ++i) {
    const int32_t node = h.nodes[i];
    const size_t c = static_cast<size_t>(node - vertex_count);
    const int32_t kept = table.kept_child[c], removed = table.removed_child[c];
    const Quadric merged = quadrics_[static_cast<size_t>(kept)] + quadrics_[static_cast<size_t>(removed)];
    quadrics_[static_cast<size_t>(node)] = merged;
    const double cost = merged.evaluate(point(t, table.representative[static_cast<size_t>(node)]));
    report.max_cost[c] = report.use_counts[c] == 0 ? cost : std::max(report.max_cost[c], cost);
    report.use_counts[c] += 1;

    // Error bound: the farthest input vertex of the cluster from the node's position, then
    // the largest bound of the children and of the dependencies (all earlier in h).
    const Eigen::Vector3d centre = point(t, table.representative[static_cast<size_t>(node)]);
    double farthest = 0.0;
    stack_.assign({kept, removed});
    while (!stack_.empty()) {
      const int32_t x = stack_.back();
      stack_.pop_back();
      if (x < vertex_count) {
        farthest = std::max(farthest, (point(t, x) - centre).squaredNorm());
        continue;
      }
      const size_t cx = static_cast<size_t>(x - vertex_count);
      stack_.push_back(table.kept_child[cx]);
      stack_.push_back(table.removed_child[cx]);
    }
    double bound = std::sqrt(farthest);
    bound = std::max({bound, bound_[static_cast<size_t>(kept)], bound_[static_cast<size_t>(removed)]});
    for (int32_t d = h.dep_offsets[i]; d < h.dep_offsets[i + 1]; ++d)
      bound = std::max(bound, bound_[static_cast<size_t>(h.dep_nodes[static_cast<size_t>(d)])]);
    bound_[static_cast<size_t>(node)] = bound;

    alive_[c].add(t);
    for (int32_t d = h.dep_offsets[i]; d < h.dep_offsets[i + 1]; ++d) links_[c].add(h.dep_nodes[static_cast<size_t>(d)], t);
    errors_[c].append({t, t + 1}, detail::encode_error(bound, scale_));
  }
}

void FieldBuilder::finish(const CollapseTable& table, detail::TdagData& data) {
  const size_t collapse_count = table.collapse_count();
  data.kept_child = table.kept_child;
  data.removed_child = table.removed_child;
  data.killed = table.killed;
  data.alive.assign(alive_.begin(), alive_.begin() + static_cast<std::ptrdiff_t>(collapse_count));
  data.dep_offsets.assign(1, 0);
  data.error_offsets.assign(1, 0);
  for (size_t c = 0; c < collapse_count; ++c) {
    for (const auto& entry : links_[c].entries()) {
      data.dep_nodes.push_back(entry.value);
      data.dep_tags.push_back(entry.tag);
    }
    data.dep_offsets.push_back(static_cast<int32_t>(data.dep_nodes.size()));
    for (const auto& run : errors_[c].runs()) data.error_runs.push_back({run.range, run.value});
    data.error_offsets.push_back(static_cast<int32_t>(data.error_runs.size()));
  }
}

double bounding_box_diagonal(const AnimatedMeshView& mesh) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY), high = Eigen::Vector3d::Constant(-INFINITY);
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    const Eigen::Vector3d p(mesh.frames[3 * v], mesh.frames[3 * v + 1], mesh.frames[3 * v + 2]);
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  const double diagonal = (high - low).norm();
  return diagonal > 0.0 && std::isfinite(diagonal) ? diagonal : 1.0;
}

// The governing geometry (V, 3): frame 0, the average or frame k.
std::vector<float> governing_positions(const AnimatedMeshView& mesh, const TdagOptions& options) {
  const size_t per_frame = mesh.vertex_count * 3;
  if (options.governing == Governing::average) {
    std::vector<double> sum(per_frame, 0.0);
    for (size_t f = 0; f < mesh.frame_count; ++f)
      for (size_t i = 0; i < per_frame; ++i) sum[i] += mesh.frames[f * per_frame + i];
    std::vector<float> average(per_frame);
    for (size_t i = 0; i < per_frame; ++i) average[i] = static_cast<float>(sum[i] / double(mesh.frame_count));
    return average;
  }
  const size_t frame = options.governing == Governing::frame ? static_cast<size_t>(options.governing_frame) : 0;
  return {mesh.frames + frame * per_frame, mesh.frames + (frame + 1) * per_frame};
}

detail::DecimationInput decimation_input(const AnimatedMeshView& mesh, const TdagOptions& options, const float* positions) {
  detail::DecimationInput input;
  input.positions = positions;
  input.faces = mesh.faces;
  input.vertex_count = mesh.vertex_count;
  input.face_count = mesh.face_count;
  input.boundary_quadrics = options.boundary_quadrics;
  input.check_inversion = options.check_inversion;
  return input;
}

// The AQEM order over all frames, replayed on the connectivity to get the hierarchy.
Status aqem_hierarchy(const AnimatedMeshView& mesh, const TdagOptions& options, CollapseTable& table,
                      FrameHierarchy& out) {
  AqemOptions aqem;
  aqem.target_face_counts = {std::min<size_t>(4, mesh.face_count)};
  aqem.use_motion_features = options.use_motion_features;
  aqem.boundary_quadrics = options.boundary_quadrics;
  aqem.check_inversion = options.check_inversion;
  AqemResult result;
  if (mesh.face_count < 4) {
    out = FrameHierarchy{};
    out.dep_offsets.push_back(0);
    return Status::success();
  }
  if (Status status = simplify_animated(mesh, {}, aqem, result); !status) return Status::error("AQEM: " + status.message);
  detail::DecimationInput input = decimation_input(mesh, options, mesh.frames);
  input.replay_removed = result.collapses.removed.data();
  input.replay_kept = result.collapses.kept.data();
  input.replay_count = result.collapses.removed.size();
  if (Status status = detail::decimate_frame(input, table, out); !status)
    return Status::error("AQEM order: " + status.message);
  return Status::success();
}

}  // namespace

Status build_temporal_dag(const AnimatedMeshView& mesh, const TdagOptions& options, TemporalDag& out,
                          TdagBuildReport* report) {
  out = TemporalDag{};
  if (Status status = validate_animated_mesh(mesh); !status) return status;
  if (Status status = check_options(mesh, options); !status) return status;
  if (mesh.frame_count > static_cast<size_t>(INT32_MAX - 1))
    return Status::error("frames: " + std::to_string(mesh.frame_count) + " frames, more than int32 frame numbers reach");

  auto data = std::make_shared<detail::TdagData>();
  TdagBuildReport local_report;
  TdagBuildReport& rep = report ? *report : local_report;
  rep = TdagBuildReport{};
  const auto frame_count = static_cast<int32_t>(mesh.frame_count);
  data->frame_count = frame_count;
  data->vertex_count = static_cast<int32_t>(mesh.vertex_count);
  data->faces.assign(mesh.faces, mesh.faces + mesh.face_count * 3);
  data->affine_base = options.affine_base;
  data->governing = options.governing;
  data->governing_frame = options.governing == Governing::frame ? options.governing_frame : 0;
  data->history_weight = options.governing == Governing::online ? options.history_weight : 0.0;
  data->scale = bounding_box_diagonal(mesh);

  // Section 3: the affine split.
  auto start = std::chrono::steady_clock::now();
  AffineSplit split;
  if (Status status = affine_split(mesh, options.affine_base, split); !status) return status;
  data->maps = std::move(split.maps);
  data->residuals = std::move(split.residuals);
  rep.seconds_affine = seconds_since(start);

  // Section 4: the hierarchy (one order, or one per frame online) and the per-frame fields.
  CollapseTable table(data->vertex_count);
  FieldBuilder fields(mesh, options, data->scale);
  auto progress = [&](size_t done) {
    if (options.progress) options.progress(done, mesh.frame_count);
  };
  if (options.governing != Governing::online) {
    start = std::chrono::steady_clock::now();
    FrameHierarchy hierarchy;
    if (options.governing == Governing::aqem) {
      if (Status status = aqem_hierarchy(mesh, options, table, hierarchy); !status) return status;
    } else {
      const std::vector<float> positions = governing_positions(mesh, options);
      if (Status status = detail::decimate_frame(decimation_input(mesh, options, positions.data()), table, hierarchy);
          !status)
        return status;
    }
    rep.seconds_hierarchy = seconds_since(start);
    progress(0);
    start = std::chrono::steady_clock::now();
    for (int32_t t = 0; t < frame_count; ++t) {
      fields.add_frame(t, table, hierarchy, rep);
      progress(static_cast<size_t>(t) + 1);
    }
    rep.seconds_fields = seconds_since(start);
  } else {
    FrameHierarchy previous, current;
    progress(0);
    for (int32_t t = 0; t < frame_count; ++t) {
      start = std::chrono::steady_clock::now();
      const float* positions = mesh.frames + static_cast<size_t>(t) * mesh.vertex_count * 3;
      detail::DecimationInput input = decimation_input(mesh, options, positions);
      std::unique_ptr<HistoryPriority> history;
      if (t > 0 && options.history_weight > 0.0) {
        history = std::make_unique<HistoryPriority>(table, previous, options.history_weight);
        input.priority = history.get();
      }
      if (Status status = detail::decimate_frame(input, table, current); !status)
        return Status::error("frame " + std::to_string(t) + ": " + status.message);
      rep.seconds_hierarchy += seconds_since(start);
      start = std::chrono::steady_clock::now();
      fields.add_frame(t, table, current, rep);
      rep.seconds_fields += seconds_since(start);
      std::swap(previous, current);
      progress(static_cast<size_t>(t) + 1);
    }
  }
  fields.finish(table, *data);
  if (Status status = detail::derive_links(*data); !status) return Status::error("internal: " + status.message);
  out.data_ = std::move(data);
  return Status::success();
}

}  // namespace animlod
