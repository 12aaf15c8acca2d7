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
//                    tagged runs (Section 2), so that a tolerance query always gives a valid cut;
//                    with one hierarchy for all frames, threads measure a frame each.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "animlod/aqem.hpp"
#include "animlod/tdag.hpp"
#include "collapse_engine.hpp"
#include "mesh_preparation.hpp"
#include "mesh_validation_detail.hpp"
#include "phase_timer.hpp"
#include "tdag_data.hpp"
#include "tdag_hierarchy.hpp"
#include "tdag_policy.hpp"
#include "worker_threads.hpp"

namespace animlod {

namespace {

using detail::CollapseTable;
using detail::FrameHierarchy;
using detail::Quadric;

Status check_options(const AnimatedMeshView& mesh, const TdagOptions& options) {
  if (options.governing == Governing::frame &&
      (options.governing_frame < 0 || static_cast<size_t>(options.governing_frame) >= mesh.frame_count))
    return Status::error("governing_frame: frame " + std::to_string(options.governing_frame) + " outside [0, " +
                         std::to_string(mesh.frame_count) + ")");
  if (!(std::isfinite(options.history_weight) && options.history_weight >= 0.0))
    return Status::error("history_weight: must be finite and >= 0, got " + std::to_string(options.history_weight));
  return Status::success();
}

// The TDAG's vertices: the prepared points, each an input vertex's position (point_source), read
// from the input's frames (a copy of a long dense clip's frames would cost as much as the
// input). A face repeated in the reverse turn (a two-sided sheet) leaves the surface as AQEM's
// does: kept, both sides were cut apart at every edge and locked, and nothing collapsed.
struct PointMesh {
  const AnimatedMeshView& input;
  detail::PreparedMesh prepared;
  std::vector<std::vector<int32_t>> twins;  // (P,) other points cut from the same input vertex

  PointMesh(const AnimatedMeshView& mesh, bool weld) : input(mesh) {
    detail::WeldInput options;
    options.weld = weld;
    options.mirror_two_sided = true;
    prepared = detail::prepare_mesh(mesh, options);
    const size_t point_count = prepared.point_source.size();
    twins.resize(point_count);
    if (prepared.split_points == 0) return;
    std::vector<std::pair<int32_t, int32_t>> by_source;
    for (size_t p = 0; p < point_count; ++p) by_source.emplace_back(prepared.point_source[p], static_cast<int32_t>(p));
    std::sort(by_source.begin(), by_source.end());
    for (size_t i = 0; i < by_source.size();) {
      size_t j = i;
      while (j < by_source.size() && by_source[j].first == by_source[i].first) ++j;
      for (size_t a = i; a < j; ++a)
        for (size_t b = i; b < j; ++b)
          if (a != b) twins[static_cast<size_t>(by_source[a].second)].push_back(by_source[b].second);
      i = j;
    }
  }

  size_t point_count() const { return prepared.point_source.size(); }
  size_t face_count() const { return prepared.faces.size() / 3; }
  // The point positions (P, 3) of input positions (V, 3) into `out`.
  void gather(const float* positions, std::vector<float>& out) const {
    out.resize(point_count() * 3);
    for (size_t p = 0; p < point_count(); ++p)
      std::copy_n(positions + static_cast<size_t>(prepared.point_source[p]) * 3, 3, &out[p * 3]);
  }
  // Frame t's.
  void gather_frame(size_t frame, std::vector<float>& out) const {
    gather(input.frames + frame * input.vertex_count * 3, out);
  }
};

// One frame's fields of a hierarchy's collapses, in its order: the cost c_{i,t} and the code of
// the error bound. A frame's do not depend on the other frames', so threads measure several.
struct FrameFields {
  std::vector<double> costs;
  std::vector<uint16_t> codes;
};

// A measuring thread's scratch, over the nodes (V + C).
struct FieldScratch {
  std::vector<Quadric> quadrics;
  std::vector<double> bound;    // monotone bound in the frame
  std::vector<float> positions; // (V, 3) the frame's
  std::vector<float> ordered;   // (V, 3) the frame's positions in ClusterRanges::leaves order
};

// The input vertices of every node's cluster in a hierarchy as one range of a depth-first order
// of the vertices: a node's farthest vertex is then sought in one contiguous run of a frame's
// positions instead of by walking its subtree through the frame at random.
struct ClusterRanges {
  std::vector<int32_t> leaves;  // (V,) the vertices, each cluster's contiguous
  std::vector<int32_t> begin;   // (V + C,) a node's first position in `leaves`
  std::vector<int32_t> count;   // (V + C,) its cluster's vertex count

  ClusterRanges(const CollapseTable& table, const FrameHierarchy& h) {
    const int32_t vertex_count = table.vertex_count();
    const size_t node_count = table.representative.size();
    begin.assign(node_count, -1);
    count.assign(node_count, 1);
    std::vector<uint8_t> has_parent(node_count, 0);
    for (const int32_t node : h.nodes) {  // children before parents
      const auto c = static_cast<size_t>(node - vertex_count);
      count[static_cast<size_t>(node)] = count[static_cast<size_t>(table.kept_child[c])] +
                                         count[static_cast<size_t>(table.removed_child[c])];
      has_parent[static_cast<size_t>(table.kept_child[c])] = has_parent[static_cast<size_t>(table.removed_child[c])] = 1;
    }
    int32_t next = 0;
    for (int32_t v = 0; v < vertex_count; ++v)  // vertices no collapse of h takes
      if (!has_parent[static_cast<size_t>(v)]) begin[static_cast<size_t>(v)] = next++;
    for (auto it = h.nodes.rbegin(); it != h.nodes.rend(); ++it) {  // parents before children
      const auto node = static_cast<size_t>(*it);
      if (!has_parent[node]) {
        begin[node] = next;
        next += count[node];
      }
      const size_t c = node - static_cast<size_t>(vertex_count);
      begin[static_cast<size_t>(table.kept_child[c])] = begin[node];
      begin[static_cast<size_t>(table.removed_child[c])] = begin[node] + count[static_cast<size_t>(table.kept_child[c])];
    }
    leaves.resize(static_cast<size_t>(vertex_count));
    for (int32_t v = 0; v < vertex_count; ++v) leaves[static_cast<size_t>(begin[static_cast<size_t>(v)])] = v;
  }
};

// Per-frame fields of the collapses, measured frame by frame and recorded in frame order.
class FieldBuilder {
 public:
  // `boundary`: the points' boundary sides, or null without boundary quadrics.
  FieldBuilder(const PointMesh& points, const std::vector<detail::BoundarySide>* boundary, double scale)
      : points_(points), boundary_(boundary), scale_(scale) {}

  // Frame t's fields of hierarchy h (its collapses are already in `table`); safe on several
  // threads at once, each with its own scratch.
  void measure(int32_t t, const CollapseTable& table, const FrameHierarchy& h, const ClusterRanges& clusters,
               FieldScratch& scratch, FrameFields& out) const;
  // Adds measured frame t to the time-tagged fields and the report; frames in increasing order.
  void record(int32_t t, const CollapseTable& table, const FrameHierarchy& h, const FrameFields& fields,
              TdagBuildReport& report);
  void finish(const CollapseTable& table, detail::TdagData& data);

 private:
  void grow(size_t collapse_count, TdagBuildReport& report) {
    if (alive_.size() >= collapse_count) return;
    alive_.resize(collapse_count);
    links_.resize(collapse_count);
    report.max_cost.resize(collapse_count, 0.0);
    report.use_counts.resize(collapse_count, 0);
  }

  const PointMesh& points_;
  const std::vector<detail::BoundarySide>* boundary_;
  double scale_;
  std::vector<TimeTag> alive_;                   // (C,)
  std::vector<TaggedSet<int32_t>> links_;        // (C,) dependencies
  // Frame t's error codes of the collapses known then (C_t, in collapse order; kNoCode for those
  // not in its hierarchy): an online build's collapse count grows with the frames.
  std::vector<std::vector<uint16_t>> code_rows_;
};

void FieldBuilder::measure(int32_t t, const CollapseTable& table, const FrameHierarchy& h,
                           const ClusterRanges& clusters, FieldScratch& scratch, FrameFields& out) const {
  const int32_t vertex_count = table.vertex_count();
  const size_t node_count = table.representative.size();
  std::vector<Quadric>& quadrics = scratch.quadrics;
  std::vector<double>& bounds = scratch.bound;
  std::vector<float>& ordered = scratch.ordered;
  out.costs.resize(h.nodes.size());
  out.codes.resize(h.nodes.size());

  // Costs c_{i,t}: the quadric of a node is the sum of its cluster's vertex quadrics in frame t.
  points_.gather_frame(static_cast<size_t>(t), scratch.positions);
  const float* positions = scratch.positions.data();
  auto point = [&](int32_t vertex) {
    const float* p = positions + static_cast<size_t>(vertex) * 3;
    return Eigen::Vector3d(p[0], p[1], p[2]);
  };
  detail::vertex_quadrics(positions, points_.prepared.faces.data(), points_.point_count(), points_.face_count(),
                          boundary_, quadrics);
  quadrics.resize(node_count);
  bounds.assign(node_count, 0.0);
  ordered.resize(clusters.leaves.size() * 3);
  for (size_t k = 0; k < clusters.leaves.size(); ++k)
    std::copy_n(positions + 3 * static_cast<size_t>(clusters.leaves[k]), 3, &ordered[3 * k]);
  for (size_t i = 0; i < h.nodes.size(); ++i) {
    const int32_t node = h.nodes[i];
    const size_t c = static_cast<size_t>(node - vertex_count);
    const int32_t kept = table.kept_child[c], removed = table.removed_child[c];
    const Quadric merged = quadrics[static_cast<size_t>(kept)] + quadrics[static_cast<size_t>(removed)];
    quadrics[static_cast<size_t>(node)] = merged;
    out.costs[i] = merged.evaluate(point(table.representative[static_cast<size_t>(node)]));

    // Error bound: the farthest input vertex of the cluster from the node's position, then
    // the largest bound of the children and of the dependencies (all earlier in h).
    const Eigen::Vector3d centre = point(table.representative[static_cast<size_t>(node)]);
    double farthest = 0.0;
    const auto first = static_cast<size_t>(clusters.begin[static_cast<size_t>(node)]);
    const size_t end = first + static_cast<size_t>(clusters.count[static_cast<size_t>(node)]);
    for (size_t k = first; k < end; ++k) {
      const double dx = ordered[3 * k] - centre.x(), dy = ordered[3 * k + 1] - centre.y(),
                   dz = ordered[3 * k + 2] - centre.z();
      farthest = std::max(farthest, dx * dx + dy * dy + dz * dz);
    }
    double bound = std::sqrt(farthest);
    bound = std::max({bound, bounds[static_cast<size_t>(kept)], bounds[static_cast<size_t>(removed)]});
    for (int32_t d = h.dep_offsets[i]; d < h.dep_offsets[i + 1]; ++d)
      bound = std::max(bound, bounds[static_cast<size_t>(h.dep_nodes[static_cast<size_t>(d)])]);
    bounds[static_cast<size_t>(node)] = bound;
    out.codes[i] = detail::encode_error(bound, scale_);
  }
}

void FieldBuilder::record(int32_t t, const CollapseTable& table, const FrameHierarchy& h, const FrameFields& fields,
                          TdagBuildReport& report) {
  const int32_t vertex_count = table.vertex_count();
  grow(table.collapse_count(), report);
  report.collapse_counts.push_back(static_cast<int32_t>(h.nodes.size()));
  std::vector<uint16_t>& codes = code_rows_.emplace_back(table.collapse_count(), detail::kNoCode);
  for (size_t i = 0; i < h.nodes.size(); ++i) {
    const size_t c = static_cast<size_t>(h.nodes[i] - vertex_count);
    const double cost = fields.costs[i];
    report.max_cost[c] = report.use_counts[c] == 0 ? cost : std::max(report.max_cost[c], cost);
    report.use_counts[c] += 1;
    alive_[c].add(t);
    for (int32_t d = h.dep_offsets[i]; d < h.dep_offsets[i + 1]; ++d) links_[c].add(h.dep_nodes[static_cast<size_t>(d)], t);
    codes[c] = fields.codes[i];
  }
}

void FieldBuilder::finish(const CollapseTable& table, detail::TdagData& data) {
  const size_t collapse_count = table.collapse_count();
  data.kept_child = table.kept_child;
  data.removed_child = table.removed_child;
  data.killed = table.killed;
  data.alive.assign(alive_.begin(), alive_.begin() + static_cast<std::ptrdiff_t>(collapse_count));
  data.dep_offsets.assign(1, 0);
  for (size_t c = 0; c < collapse_count; ++c) {
    for (const auto& entry : links_[c].entries()) {
      data.dep_nodes.push_back(entry.value);
      data.dep_tags.push_back(entry.tag);
    }
    data.dep_offsets.push_back(static_cast<int32_t>(data.dep_nodes.size()));
  }
  // The rows into the (F, C) table, each freed once copied.
  data.codes_by_frame.assign(code_rows_.size() * collapse_count, detail::kNoCode);
  for (size_t t = 0; t < code_rows_.size(); ++t) {
    std::copy(code_rows_[t].begin(), code_rows_[t].end(), data.codes_by_frame.begin() + static_cast<std::ptrdiff_t>(t * collapse_count));
    std::vector<uint16_t>().swap(code_rows_[t]);
  }
}

// Of the points in frame 0.
double bounding_box_diagonal(const PointMesh& points) {
  std::vector<float> positions;
  points.gather_frame(0, positions);
  Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY), high = Eigen::Vector3d::Constant(-INFINITY);
  for (size_t v = 0; v < points.point_count(); ++v) {
    const Eigen::Vector3d p(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  const double diagonal = (high - low).norm();
  return diagonal > 0.0 && std::isfinite(diagonal) ? diagonal : 1.0;
}

// The governing geometry of the input vertices (V, 3): frame 0, the average or frame k.
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

// One frame's order from the collapse engine with the TDAG policy: `positions` (V, 3) are the
// input vertices in the decimated geometry; returns the order and its quadric costs.
Status decimate(const AnimatedMeshView& mesh, const PointMesh& points, const float* positions,
                const TdagOptions& options, const std::vector<detail::BoundarySide>* boundary,
                const detail::HistoryTerm* history, CollapseTable& table, FrameHierarchy& out,
                std::vector<double>& costs) {
  const AnimatedMeshView one_frame{positions, mesh.faces, 1, mesh.vertex_count, mesh.face_count};
  detail::EngineOptions engine_options;
  engine_options.check_inversion = options.check_inversion;
  const detail::CarriedData carried;
  detail::CollapseEngine engine(one_frame, points.prepared, carried, engine_options);
  std::vector<float> point_positions;
  points.gather(positions, point_positions);
  std::vector<Quadric> quadrics;
  detail::vertex_quadrics(point_positions.data(), points.prepared.faces.data(), points.point_count(),
                          points.face_count(), boundary, quadrics);
  detail::TdagCollapsePolicy policy(engine, std::move(quadrics), table, history);
  std::vector<detail::EngineLevel> levels;
  detail::EngineRecord record;
  engine.run(policy, {1}, levels, record);
  costs = policy.costs();
  return detail::record_hierarchy(points.prepared.faces.data(), points.face_count(), points.point_count(),
                                  policy.collapses(), nullptr, table, out);
}

// The AQEM order over all frames (simplify_animated's collapse record, welded as the TDAG is),
// turned into the points' hierarchy. AQEM places the merged vertex optimally; the TDAG keeps
// the position of its kept vertex.
Status aqem_hierarchy(const AnimatedMeshView& mesh, const PointMesh& points, const TdagOptions& options,
                      CollapseTable& table, FrameHierarchy& out) {
  AqemOptions aqem;
  aqem.target_face_counts = {1};
  aqem.use_motion_features = options.use_motion_features;
  aqem.boundary_quadrics = options.boundary_quadrics;
  aqem.tip_quadrics = false;  // the paper's quadrics, like the TDAG's own (Fig. 6 compares them)
  aqem.check_inversion = options.check_inversion;
  aqem.fold_limit = std::numeric_limits<double>::infinity();  // and the paper's Eq. 7 alone
  aqem.weld = options.weld;
  aqem.record_positions = false;  // the hierarchy needs the order alone
  AqemResult result;
  if (Status status = simplify_animated(mesh, {}, aqem, result); !status) return Status::error("AQEM: " + status.message);
  std::vector<detail::VertexCollapse> collapses(result.collapses.removed.size());
  for (size_t i = 0; i < collapses.size(); ++i) {
    collapses[i].removed = points.prepared.wedge_point[static_cast<size_t>(result.collapses.removed[i])];
    collapses[i].kept = points.prepared.wedge_point[static_cast<size_t>(result.collapses.kept[i])];
  }
  if (Status status = detail::record_hierarchy(points.prepared.faces.data(), points.face_count(), points.point_count(),
                                               collapses, &points.twins, table, out);
      !status)
    return Status::error("AQEM order: " + status.message);
  return Status::success();
}

}  // namespace

Status build_temporal_dag(const AnimatedMeshView& mesh, const TdagOptions& options, TemporalDag& out,
                          TdagBuildReport* report) {
  out = TemporalDag{};
  if (Status status = detail::check_sizes_values_and_indices(mesh); !status) return status;
  if (Status status = check_options(mesh, options); !status) return status;
  if (mesh.frame_count > static_cast<size_t>(INT32_MAX - 1))
    return Status::error("frames: " + std::to_string(mesh.frame_count) + " frames, more than int32 frame numbers reach");

  // The TDAG's vertices: welded points, degenerate and repeated faces dropped, non-manifold
  // spots cut apart (as the collapse engine needs them).
  PointMesh points(mesh, options.weld);
  if (points.face_count() == 0)
    return Status::error("faces: every face is degenerate (no face has three distinct positions)");

  auto data = std::make_shared<detail::TdagData>();
  TdagBuildReport local_report;
  TdagBuildReport& rep = report ? *report : local_report;
  rep = TdagBuildReport{};
  const auto frame_count = static_cast<int32_t>(mesh.frame_count);
  data->frame_count = frame_count;
  data->vertex_count = static_cast<int32_t>(points.point_count());
  data->faces = points.prepared.faces;
  data->input_points = points.prepared.wedge_point;
  for (int32_t source : points.prepared.mirror_sources) data->two_sided.push_back(source >= 0 ? 1 : 0);
  // A vertex only the turned-over copies use stands for its front counterpart's point.
  const std::vector<int32_t>& mirrors = points.prepared.mirror_vertices;
  for (size_t i = 0; i < mirrors.size(); i += 2) {
    int32_t& point = data->input_points[static_cast<size_t>(mirrors[i])];
    if (point < 0) point = data->input_points[static_cast<size_t>(mirrors[i + 1])];
  }
  data->affine_base = options.affine_base;
  data->governing = options.governing;
  data->governing_frame = options.governing == Governing::frame ? options.governing_frame : 0;
  data->history_weight = options.governing == Governing::online ? options.history_weight : 0.0;
  data->scale = bounding_box_diagonal(points);

  // Section 3: the affine split.
  {
    const detail::PhaseTimer timer(rep.seconds_affine);
    AffineSplit split;
    if (Status status = affine_split(mesh, points.prepared.point_source.data(), points.point_count(),
                                     options.affine_base, split);
        !status)
      return status;
    data->maps = std::move(split.maps);
    data->residuals = std::move(split.residuals);
  }

  // Section 4: the hierarchy (one order, or one per frame online) and the per-frame fields.
  CollapseTable table(data->vertex_count);
  const std::vector<detail::BoundarySide> boundary =
      options.boundary_quadrics ? detail::boundary_sides(points.prepared.faces.data(), points.face_count())
                                : std::vector<detail::BoundarySide>{};
  const std::vector<detail::BoundarySide>* boundary_or_null = options.boundary_quadrics ? &boundary : nullptr;
  FieldBuilder fields(points, boundary_or_null, data->scale);
  auto progress = [&](size_t done) {
    if (options.progress) options.progress(done, mesh.frame_count);
  };
  std::vector<double> costs;
  if (options.governing != Governing::online) {
    FrameHierarchy hierarchy;
    {
      const detail::PhaseTimer timer(rep.seconds_hierarchy);
      if (options.governing == Governing::aqem) {
        if (Status status = aqem_hierarchy(mesh, points, options, table, hierarchy); !status) return status;
      } else {
        const std::vector<float> positions = governing_positions(mesh, options);
        if (Status status = decimate(mesh, points, positions.data(), options, boundary_or_null, nullptr, table,
                                     hierarchy, costs);
            !status)
          return Status::error("internal: " + status.message);
      }
    }
    progress(0);
    const detail::PhaseTimer timer(rep.seconds_fields);
    // One hierarchy for every frame: threads measure a frame each, recorded in frame order
    // (recording on the threads too, each its share of the collapses, gained nothing).
    const auto workers = static_cast<int32_t>(std::min<size_t>(thread_limit(), mesh.frame_count));
    const ClusterRanges clusters(table, hierarchy);
    std::vector<FieldScratch> scratch(static_cast<size_t>(workers));
    std::vector<FrameFields> measured(static_cast<size_t>(workers));
    for (int32_t first = 0; first < frame_count; first += workers) {
      const auto count = static_cast<size_t>(std::min(workers, frame_count - first));
      detail::run_in_ranges(count, count, [&](size_t k, size_t, size_t) {
        fields.measure(first + static_cast<int32_t>(k), table, hierarchy, clusters, scratch[k], measured[k]);
      });
      for (size_t k = 0; k < count; ++k) fields.record(first + static_cast<int32_t>(k), table, hierarchy, measured[k], rep);
      progress(static_cast<size_t>(first) + count);
    }
  } else {
    FrameHierarchy previous, current;
    std::vector<double> previous_costs;
    FieldScratch scratch;
    FrameFields measured;
    progress(0);
    for (int32_t t = 0; t < frame_count; ++t) {
      {
        const detail::PhaseTimer timer(rep.seconds_hierarchy);
        const float* positions = mesh.frames + static_cast<size_t>(t) * mesh.vertex_count * 3;
        std::unique_ptr<detail::HistoryTerm> history;
        if (t > 0 && options.history_weight > 0.0)
          history = std::make_unique<detail::HistoryTerm>(table, previous, previous_costs, options.history_weight);
        if (Status status = decimate(mesh, points, positions, options, boundary_or_null, history.get(), table,
                                     current, costs);
            !status)
          return Status::error("internal: frame " + std::to_string(t) + ": " + status.message);
      }
      {
        const detail::PhaseTimer timer(rep.seconds_fields);
        fields.measure(t, table, current, ClusterRanges(table, current), scratch, measured);
        fields.record(t, table, current, measured, rep);
      }
      std::swap(previous, current);
      previous_costs = costs;
      progress(static_cast<size_t>(t) + 1);
    }
  }
  fields.finish(table, *data);
  if (Status status = detail::derive_links(*data); !status) return Status::error("internal: " + status.message);
  out.data_ = std::move(data);
  return Status::success();
}

}  // namespace animlod
