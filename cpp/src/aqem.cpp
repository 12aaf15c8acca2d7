// AQEM: animated quadric error metric simplification (Yang et al. 2019, "Animated mesh
// simplification based on motion features in visual sensor networks"), as a cost and placement
// policy of the collapse engine.
//
// Implements the 12-step outline of the paper:
//   steps 1-2  per-point quadrics of every frame (Eqs. 1-4; block-diagonal, so F quadrics of
//              ten doubles per point, stored contiguously per point), plus a point quadric at
//              every needle tip (option tip_quadrics, needle_tips.hpp; not in the paper);
//   steps 3-4  motion features and vertex weights (motion_features.cpp);
//   steps 5-6  per edge: merged quadric Q = Q_i + Q_j (the text after Eq. 4; step 5.1 writes
//              (Q_i + Q_j) / 2, which only rescales), weight w = (w_i + w_j) / 2, optimal
//              position per frame (Eq. 5), cost w * sum_f Q_f(v_f) (Eq. 6);
//   steps 7-12 the collapse engine (collapse_engine.cpp): heap, legality (link condition, seams,
//              Eq. 7's inversion test across frames), collapse, re-key; the policy passes the
//              weight on (step 9).
#include "animlod/aqem.hpp"

#include <algorithm>
#include <cmath>
#include <future>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "animlod/motion_features.hpp"
#include "collapse_engine.hpp"
#include "frame_sampling.hpp"
#include "mesh_preparation.hpp"
#include "mesh_validation_detail.hpp"
#include "needle_tips.hpp"
#include "phase_timer.hpp"
#include "quadric.hpp"
#include "worker_threads.hpp"

namespace animlod {

namespace {

using detail::Candidate;
using detail::CollapseEngine;
using detail::Quadric;

// Checks the face counts against the mesh and resolves the level targets (finest first); the
// rest was checked by check_aqem_options. `face_count` is M', the faces left after preparation;
// `input_faces` is M.
Status resolve_targets(size_t face_count, size_t input_faces, const AqemOptions& options,
                       std::vector<size_t>& targets) {
  targets.clear();
  if (!options.target_face_counts.empty()) {
    for (size_t count : options.target_face_counts) {
      if (count > input_faces)
        return Status::error("target_face_counts: " + std::to_string(count) + " outside [1, " +
                             std::to_string(input_faces) + "] (the mesh has " + std::to_string(input_faces) +
                             " faces)");
      targets.push_back(count);
    }
  } else {
    for (double ratio : options.target_ratios) {
      const auto count = static_cast<size_t>(std::llround(ratio * static_cast<double>(face_count)));
      targets.push_back(std::max<size_t>(count, 1));
    }
  }
  std::sort(targets.begin(), targets.end(), std::greater<>());
  return Status::success();
}

Status resolve_frames(const AnimatedMeshView& mesh, const AqemOptions& options, std::vector<int32_t>& frames) {
  if (!options.frame_subset.empty()) {
    frames = options.frame_subset;
    for (int32_t f : frames)
      if (static_cast<size_t>(f) >= mesh.frame_count)
        return Status::error("frame_subset: frame " + std::to_string(f) + " outside [0, " +
                             std::to_string(mesh.frame_count) + ")");
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  } else if (options.max_frames > 0 && options.max_frames < mesh.frame_count) {
    frames = detail::sample_frames(mesh, options.max_frames);
  } else if (const size_t fit = options.quadric_memory_limit / (sizeof(Quadric) * mesh.vertex_count);
             options.max_frames == 0 && options.quadric_memory_limit > 0 && fit < mesh.frame_count) {
    frames = detail::sample_frames(mesh, std::max<size_t>(fit, 1));
  } else {
    frames.resize(mesh.frame_count);
    for (size_t f = 0; f < mesh.frame_count; ++f) frames[f] = static_cast<int32_t>(f);
  }
  return Status::success();
}

// The pointers and counts must agree before any value is read.
Status validate_vertex_data_layout(const AqemVertexData& data) {
  if (data.attribute_count > 0 && !data.attributes)
    return Status::error("attributes: attribute_count is " + std::to_string(data.attribute_count) +
                         " but attributes is null");
  if (data.position_attribute_count > 0 && !data.position_attributes)
    return Status::error("position_attributes: position_attribute_count is " +
                         std::to_string(data.position_attribute_count) + " but position_attributes is null");
  if ((data.skin_joints == nullptr) != (data.skin_weights == nullptr))
    return Status::error("skin_joints and skin_weights: give both or neither");
  return Status::success();
}

Status validate_vertex_data(const AnimatedMeshView& mesh, const AqemVertexData& data) {
  if (Status status = validate_vertex_data_layout(data); !status) return status;
  for (size_t v = 0; v < mesh.vertex_count; ++v) {
    if (data.importance && !(std::isfinite(data.importance[v]) && data.importance[v] > 0.0f))
      return Status::error("importance: vertex " + std::to_string(v) + " has a non-positive or non-finite weight");
    for (size_t a = 0; a < data.attribute_count; ++a)
      if (!std::isfinite(data.attributes[v * data.attribute_count + a]))
        return Status::error("attributes: vertex " + std::to_string(v) + " has a non-finite value");
    for (size_t b = 0; b < data.position_attribute_count; ++b)
      if (!std::isfinite(data.position_attributes[v * data.position_attribute_count + b]))
        return Status::error("position_attributes: vertex " + std::to_string(v) + " has a non-finite value");
    for (size_t k = 0; k < data.influence_count && data.skin_joints; ++k) {
      const size_t i = v * data.influence_count + k;
      if (data.skin_joints[i] < 0)
        return Status::error("skin_joints: vertex " + std::to_string(v) + " has a negative joint index");
      if (!(std::isfinite(data.skin_weights[i]) && data.skin_weights[i] >= 0.0f))
        return Status::error("skin_weights: vertex " + std::to_string(v) + " has a negative or non-finite weight");
    }
  }
  return Status::success();
}

// The frames of the points, (F, P, 3): the input's own frames when nothing was welded or split.
class PointFrames {
 public:
  PointFrames(const AnimatedMeshView& mesh, const detail::PreparedMesh& prepared) {
    const size_t point_count = prepared.point_source.size();
    view_ = {nullptr, prepared.faces.data(), mesh.frame_count, point_count, prepared.faces.size() / 3};
    bool identity = point_count == mesh.vertex_count;
    for (size_t p = 0; identity && p < point_count; ++p) identity = prepared.point_source[p] == static_cast<int32_t>(p);
    if (identity) {
      view_.frames = mesh.frames;
      return;
    }
    copy_.resize(mesh.frame_count * point_count * 3);
    for (size_t frame = 0; frame < mesh.frame_count; ++frame)
      for (size_t p = 0; p < point_count; ++p)
        std::copy_n(mesh.frames + (frame * mesh.vertex_count + static_cast<size_t>(prepared.point_source[p])) * 3, 3,
                    &copy_[(frame * point_count + p) * 3]);
    view_.frames = copy_.data();
  }
  const AnimatedMeshView& view() const { return view_; }
  // Frees a copy once the quadrics and features are made: the collapses read the engine's own
  // positions, and a long clip's levels and record are as large as the frames.
  void release() {
    std::vector<float>().swap(copy_);
    view_.frames = nullptr;
  }

 private:
  AnimatedMeshView view_;
  std::vector<float> copy_;
};

// Steps 1-2's part that needs no connectivity (Eqs. 1-4): every face's plane in every used
// frame summed into its three points' quadrics of that frame, the planes counted per point (so
// that the error can be a mean; a face with no area in a frame counts there as a plane at
// distance 0), and the needle tips (option tip_quadrics). It reads only the prepared faces and
// the points' frames, so simplify_animated sums it while the engine builds OpenMesh's
// connectivity; AqemPolicy then adds the sides' planes and the tips' point quadrics.
struct FaceQuadrics {
  std::vector<Quadric> quadrics;     // (P, K) per-frame quadrics, contiguous per point
  std::vector<double> plane_counts;  // (P,)
  std::vector<int32_t> tips;         // needle tips in every used frame
};

Eigen::Vector3d point_position(const AnimatedMeshView& points, int32_t point, size_t frame) {
  const float* p = points.frames + (frame * points.vertex_count + static_cast<size_t>(point)) * 3;
  return {p[0], p[1], p[2]};
}

// Needle tips in every used frame: a spike stays one, while a point that folds into a narrow
// cone in some poses only (a bent finger, a creased strip) is no needle. After the first frame
// only the tips so far are looked at. The search walks every face, so two workers take half of
// the points each.
std::vector<int32_t> tips_in_every_frame(const std::vector<int32_t>& faces, const AnimatedMeshView& points,
                                         const std::vector<int32_t>& frames) {
  const size_t workers = detail::halves_from(faces.size(), 3 * 65536);
  std::vector<uint8_t> tip_so_far(points.vertex_count, 1);
  std::vector<std::vector<int32_t>> found(workers);
  std::vector<int32_t> tips;
  for (const int32_t frame : frames) {
    auto position_of = [&](int32_t point) { return point_position(points, point, static_cast<size_t>(frame)); };
    detail::run_in_ranges(points.vertex_count, workers, [&](size_t begin, size_t end, size_t worker) {
      found[worker] = detail::find_needle_tips(faces, static_cast<int32_t>(begin), static_cast<int32_t>(end),
                                               position_of, tip_so_far.data());
    });
    tips.clear();
    for (const std::vector<int32_t>& part : found) tips.insert(tips.end(), part.begin(), part.end());
    std::fill(tip_so_far.begin(), tip_so_far.end(), 0);
    for (int32_t tip : tips) tip_so_far[tip] = 1;
    if (tips.empty()) break;
  }
  return tips;
}

// faces: the prepared faces (M', 3); points: their points' frames (F, P, 3).
FaceQuadrics face_quadrics(const std::vector<int32_t>& faces, const AnimatedMeshView& points,
                           const std::vector<int32_t>& frames, bool tip_quadrics) {
  const size_t point_count = points.vertex_count, used_count = frames.size();
  auto position = [&](int32_t point, size_t frame) { return point_position(points, point, frame); };
  FaceQuadrics out;
  out.quadrics.assign(point_count * used_count, Quadric{});
  out.plane_counts.assign(point_count, 0.0);
  for (const int32_t point : faces) out.plane_counts[point] += 1.0;
  if (tip_quadrics) out.tips = tips_in_every_frame(faces, points, frames);
  // Two workers take half of the frames each, or with one frame half of the points (a face
  // between the halves is planed by both); every quadric sums its planes in the same order as
  // one worker would.
  const size_t workers = detail::halves_from(faces.size() * used_count, 3 * 65536);
  detail::run_in_ranges(workers, workers, [&](size_t, size_t, size_t worker) {
    size_t frame_begin = 0, frame_end = used_count;
    int32_t point_begin = 0, point_end = static_cast<int32_t>(point_count);
    if (workers == 2 && used_count >= 2) {
      frame_begin = used_count * worker / 2;
      frame_end = used_count * (worker + 1) / 2;
    } else if (workers == 2) {
      (worker == 0 ? point_end : point_begin) = static_cast<int32_t>(point_count / 2);
    }
    auto has = [&](int32_t point) { return point >= point_begin && point < point_end; };
    for (size_t f = 0; f < faces.size() / 3; ++f) {
      const int32_t* v = &faces[3 * f];
      if (!has(v[0]) && !has(v[1]) && !has(v[2])) continue;
      for (size_t k = frame_begin; k < frame_end; ++k) {
        const size_t frame = static_cast<size_t>(frames[k]);
        const Eigen::Vector3d p0 = position(v[0], frame), p1 = position(v[1], frame), p2 = position(v[2], frame);
        const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0);
        const double length = normal.norm();
        if (length == 0.0) continue;  // a face with no area in this frame has no plane
        const Quadric plane = Quadric::plane(normal / length, p0, 1.0);
        for (int corner = 0; corner < 3; ++corner)
          if (has(v[corner])) out.quadrics[static_cast<size_t>(v[corner]) * used_count + k] += plane;
      }
    }
  });
  return out;
}

// Steps 1-2 and 5-6 of the paper for the collapse engine.
class AqemPolicy final : public detail::CollapsePolicy {
 public:
  // Completes the face quadrics (FaceQuadrics) with the border and seam sides' planes and the
  // needle tips' point quadrics.
  AqemPolicy(const CollapseEngine& engine, const AqemOptions& options, const std::vector<int32_t>& frames,
             std::vector<double> weights, FaceQuadrics face)
      : engine_(engine),
        options_(options),
        frames_(frames),
        used_count_(frames.size()),
        vertex_weights_(std::move(weights)),
        quadrics_(std::move(face.quadrics)),
        plane_counts_(std::move(face.plane_counts)),
        tips_(std::move(face.tips)),
        scratch_(kWorkers) {
    add_side_quadrics();
  }

  void evaluate(Candidate& candidate) override { evaluate_with(candidate, scratch_[0]); }
  // Collapse passes: costs and collapses on both cores (an evaluation reads the two points'
  // quadrics, weights and positions; a merge writes the kept point's).
  size_t concurrency() const override { return kWorkers; }
  void evaluate_concurrently(Candidate& candidate, size_t worker) override {
    evaluate_with(candidate, scratch_[worker]);
  }
  void place(Candidate& candidate, std::vector<Eigen::Vector3d>& placed) override {
    place_concurrently(candidate, placed, 0);
  }
  void place_concurrently(Candidate& candidate, std::vector<Eigen::Vector3d>& placed, size_t worker) override;
  void merge(const Candidate& candidate) override {
    Quadric* kept_quadrics = quadrics_of(candidate.kept);
    const Quadric* removed_quadrics = quadrics_of(candidate.removed);
    for (size_t k = 0; k < used_count_; ++k) kept_quadrics[k] += removed_quadrics[k];
    plane_counts_[candidate.kept] += plane_counts_[candidate.removed];
    vertex_weights_[candidate.kept] = weight(candidate);  // step 9: the weight passes on
  }

 private:
  void add_side_quadrics();
  void add_side_planes(const std::vector<std::array<int32_t, 3>>& sides);
  // The last evaluation of a worker, which its placement reads; a cache line of its own, as
  // every evaluation writes it (sharing one, the two workers' evaluations took 1.5x as long).
  struct alignas(64) Scratch {
    detail::MergedMinimizers minimizers;  // Eq. 5 in the quadrics' frames
    int fallback = 0;  // kFallbacks index for the frames Eq. 5 leaves unsolved; -1: on the edge at t
  };
  static constexpr double kFallbacks[3] = {0.0, 1.0, 0.5};  // kept, removed, midpoint along the edge
  static constexpr size_t kWorkers = 2;
  void evaluate_with(Candidate& candidate, Scratch& scratch) const;
  void evaluate_on_edge(Candidate& candidate, bool pinned) const;
  double rms_plane_distance(const Candidate& candidate, double total) const;
  double weight(const Candidate& candidate) const {
    return 0.5 * (vertex_weights_[candidate.kept] + vertex_weights_[candidate.removed]);
  }
  Quadric* quadrics_of(int32_t point) { return &quadrics_[static_cast<size_t>(point) * used_count_]; }
  const Quadric* quadrics_of(int32_t point) const { return &quadrics_[static_cast<size_t>(point) * used_count_]; }

  const CollapseEngine& engine_;
  const AqemOptions& options_;
  const std::vector<int32_t>& frames_;  // frames whose quadrics are used (K)
  const size_t used_count_;             // K
  std::vector<double> vertex_weights_;  // (P,) Eq. 6 weights, passed on by collapses (step 9)
  std::vector<Quadric> quadrics_;       // (P, K) per-frame quadrics, contiguous per point
  std::vector<double> plane_counts_;    // (P,) planes summed into each of the point's K quadrics
  std::vector<int32_t> tips_;           // needle tips in every used frame (option tip_quadrics)
  std::vector<Scratch> scratch_;  // (kWorkers,) each holds its worker's last placement
};

// Border and seam sides add a plane through the side perpendicular to its face (option
// boundary_quadrics), counted with the point's planes, and needle tips a point quadric (option
// tip_quadrics): after the face planes, in the order one pass over everything would add them.
void AqemPolicy::add_side_quadrics() {
  if (options_.boundary_quadrics)
    for (const auto* sides : {&engine_.border_sides(), &engine_.seam_sides()}) {
      for (const auto& side : *sides) {
        plane_counts_[side[0]] += 1.0;
        plane_counts_[side[1]] += 1.0;
      }
      add_side_planes(*sides);
    }
  // Every needle tip gets, in each used frame, the squared distance from where it is, once per
  // plane of the point (so it weighs like the planes do): moving a tip then costs at least its
  // displacement, which its nearly parallel planes do not charge.
  for (size_t k = 0; k < used_count_; ++k)
    for (int32_t tip : tips_)
      quadrics_of(tip)[k] += Quadric::point(engine_.position(tip, static_cast<size_t>(frames_[k])), plane_counts_[tip]);
}

// A plane through each side (a, b) perpendicular to the face (a, b, c) beside it.
void AqemPolicy::add_side_planes(const std::vector<std::array<int32_t, 3>>& sides) {
  for (const auto& [a, b, c] : sides)
    for (size_t k = 0; k < used_count_; ++k) {
      const size_t frame = static_cast<size_t>(frames_[k]);
      const Eigen::Vector3d pa = engine_.position(a, frame), pb = engine_.position(b, frame),
                            pc = engine_.position(c, frame);
      const Eigen::Vector3d face_normal = (pb - pa).cross(pc - pa);
      const Eigen::Vector3d normal = (pb - pa).cross(face_normal);
      const double length = normal.norm();
      if (length == 0.0) continue;
      const Quadric plane = Quadric::plane(normal / length, pa, 1.0);
      quadrics_of(a)[k] += plane;
      quadrics_of(b)[k] += plane;
    }
}

// Steps 5-6: merged quadric, weight and optimal placement per used frame (Eq. 5); cost of
// Eq. 6. Frames whose X is singular or whose minimiser is out of the edge's reach share one
// fallback, the best in sum over those frames of the kept endpoint, the removed endpoint and the
// midpoint (ties in that order), so that the point does not slide to a different spot of a flat
// region in every frame. Leaves what the placement needs in scratch (place_concurrently): most
// evaluations only key an edge.
void AqemPolicy::evaluate_with(Candidate& candidate, Scratch& scratch) const {
  const bool pinned = engine_.locked(candidate.kept);
  if (pinned || options_.placement == Placement::on_edge) {
    scratch.fallback = -1;
    return evaluate_on_edge(candidate, pinned);
  }
  const Quadric* kept_quadrics = quadrics_of(candidate.kept);
  const Quadric* removed_quadrics = quadrics_of(candidate.removed);
  double fallback_cost[3] = {0.0, 0.0, 0.0};
  double total = 0.0;
  scratch.minimizers.solve(kept_quadrics, removed_quadrics, used_count_);
  for (size_t k = 0; k < used_count_; ++k) {
    const size_t frame = static_cast<size_t>(frames_[k]);
    const Eigen::Vector3d p_kept = engine_.position(candidate.kept, frame),
                          p_removed = engine_.position(candidate.removed, frame);
    if (scratch.minimizers.solved(k)) {
      // A minimiser farther from the edge's midpoint than the edge is long comes from a nearly
      // flat direction of the quadric (a strip of a cylinder barely bent in a frame near rest
      // put it 2.7 diagonals away): its plane distances are small, but it is no point of the
      // surface there, so the frame takes the fallback (meshoptimizer rejects an optimal
      // position outside the vertex's neighbourhood for the same reason).
      const Eigen::Vector3d from_middle = scratch.minimizers.position(k) - 0.5 * (p_kept + p_removed);
      if (from_middle.squaredNorm() <= (p_removed - p_kept).squaredNorm()) {
        total += scratch.minimizers.value(k);
        continue;
      }
      scratch.minimizers.reject(k);
    }
    const Quadric merged = kept_quadrics[k] + removed_quadrics[k];
    for (int option = 0; option < 3; ++option)
      fallback_cost[option] += merged.evaluate(p_kept + kFallbacks[option] * (p_removed - p_kept));
  }
  int fallback = 0;
  for (int option = 1; option < 3; ++option)
    if (fallback_cost[option] < fallback_cost[fallback]) fallback = option;
  total += fallback_cost[fallback];
  scratch.fallback = fallback;
  candidate.cost = weight(candidate) * total;
  candidate.error = rms_plane_distance(candidate, total);
}

// The merged quadric's `total` (Eq. 6 unweighted: sum over the K frames of the squared
// distances to its planes) over K times its plane count: an RMS plane distance that does not
// grow with the number of planes merged.
double AqemPolicy::rms_plane_distance(const Candidate& candidate, double total) const {
  const double planes = plane_counts_[candidate.kept] + plane_counts_[candidate.removed];
  return std::sqrt(total / (static_cast<double>(used_count_) * planes));
}

// Placement::on_edge (and a locked kept point, t = 0): the t in [0, 1] minimising
// sum_f Q_f(kept_f + t (removed_f - kept_f)), a quadratic in t.
void AqemPolicy::evaluate_on_edge(Candidate& candidate, bool pinned) const {
  const Quadric* kept_quadrics = quadrics_of(candidate.kept);
  const Quadric* removed_quadrics = quadrics_of(candidate.removed);
  double curvature = 0.0, slope = 0.0;
  if (!pinned) {
    for (size_t k = 0; k < used_count_; ++k) {
      const size_t frame = static_cast<size_t>(frames_[k]);
      const Eigen::Vector3d p_kept = engine_.position(candidate.kept, frame);
      (kept_quadrics[k] + removed_quadrics[k])
          .accumulate_line(p_kept, engine_.position(candidate.removed, frame) - p_kept, curvature, slope);
    }
  }
  candidate.t = curvature > 0.0 ? std::clamp(-slope / curvature, 0.0, 1.0) : (slope < 0.0 ? 1.0 : 0.0);
  double total = 0.0;
  for (size_t k = 0; k < used_count_; ++k) {
    const size_t frame = static_cast<size_t>(frames_[k]);
    const Eigen::Vector3d p_kept = engine_.position(candidate.kept, frame);
    total += (kept_quadrics[k] + removed_quadrics[k])
                 .evaluate(p_kept + candidate.t * (engine_.position(candidate.removed, frame) - p_kept));
  }
  candidate.cost = weight(candidate) * total;
  candidate.error = rms_plane_distance(candidate, total);
}

// The candidate's point in every frame F (the worker's last evaluation): its Eq. 5 placement in
// the quadrics' frames, with t the mean projection of that placement onto the edge, and
// kept + t (removed - kept) in the others. On the edge, that in every frame.
void AqemPolicy::place_concurrently(Candidate& candidate, std::vector<Eigen::Vector3d>& placed, size_t worker) {
  const Scratch& scratch = scratch_[worker];
  const bool eq5 = scratch.fallback >= 0;
  if (eq5) {
    double along = 0.0, length2 = 0.0;
    for (size_t k = 0; k < used_count_; ++k) {
      const size_t frame = static_cast<size_t>(frames_[k]);
      const Eigen::Vector3d p_kept = engine_.position(candidate.kept, frame),
                            p_removed = engine_.position(candidate.removed, frame);
      Eigen::Vector3d& v = placed[frame];
      v = scratch.minimizers.solved(k) ? scratch.minimizers.position(k)
                                       : Eigen::Vector3d(p_kept + kFallbacks[scratch.fallback] * (p_removed - p_kept));
      along += (v - p_kept).dot(p_removed - p_kept);
      length2 += (p_removed - p_kept).squaredNorm();
    }
    candidate.t = length2 > 0.0 ? std::clamp(along / length2, 0.0, 1.0) : 0.0;
  }
  size_t used = 0;
  for (size_t frame = 0; frame < engine_.frame_count(); ++frame) {
    if (eq5 && used < used_count_ && static_cast<size_t>(frames_[used]) == frame) {
      ++used;
      continue;
    }
    const Eigen::Vector3d p_kept = engine_.position(candidate.kept, frame);
    placed[frame] = p_kept + candidate.t * (engine_.position(candidate.removed, frame) - p_kept);
  }
}

AqemLevel to_level(detail::EngineLevel&& engine_level) {
  AqemLevel level;
  level.target_face_count = engine_level.target_face_count;
  level.reached = engine_level.reached;
  level.stopped_by_max_error = engine_level.stopped_by_max_error;
  level.collapse_count = engine_level.collapse_count;
  level.error = engine_level.error;
  level.faces = std::move(engine_level.faces);
  level.face_sources = std::move(engine_level.face_sources);
  level.kept_vertices = std::move(engine_level.kept_vertices);
  level.vertex_map = std::move(engine_level.vertex_map);
  level.positions = std::move(engine_level.positions);
  level.attributes = std::move(engine_level.attributes);
  level.skin_joints = std::move(engine_level.skin_joints);
  level.skin_weights = std::move(engine_level.skin_weights);
  level.position_attributes = std::move(engine_level.position_attributes);
  return level;
}

}  // namespace

Status check_aqem_options(const AqemOptions& options) {
  if (!options.target_face_counts.empty()) {
    for (size_t count : options.target_face_counts)
      if (count < 1) return Status::error("target_face_counts: 0 outside [1, M] (a level needs a face)");
  } else {
    if (options.target_ratios.empty()) return Status::error("target_ratios: no level requested");
    for (double ratio : options.target_ratios)
      if (!(ratio > 0.0 && ratio <= 1.0))
        return Status::error("target_ratios: " + std::to_string(ratio) + " outside (0, 1]");
  }
  if (std::isnan(options.max_error) || options.max_error < 0.0) return Status::error("max_error: must be >= 0");
  if (std::isnan(options.fold_limit) || options.fold_limit < 0.0) return Status::error("fold_limit: must be >= 0");
  for (int32_t f : options.frame_subset)
    if (f < 0) return Status::error("frame_subset: frame " + std::to_string(f) + " is negative");
  if (options.use_motion_features) return check_motion_feature_options(options.motion_features);
  return Status::success();
}

Status simplify_animated(const AnimatedMeshView& mesh, const AqemVertexData& vertex_data, const AqemOptions& options,
                         AqemResult& out) {
  // Everything is built in `result` and moved into `out` only on success, so that an error
  // (or an exception from the progress callback) leaves `out` empty, never half filled.
  out = AqemResult{};
  AqemResult result;
  AqemTimings& seconds = result.seconds;
  std::optional<detail::PhaseTimer> timer(std::in_place, seconds.preparation);
  if (Status status = check_aqem_options(options); !status) return status;
  if (Status status = detail::check_sizes_values_and_indices(mesh); !status) return status;
  if (Status status = validate_vertex_data(mesh, vertex_data); !status) return status;

  // Weld, drop, cut: a manifold surface of points whose corners remember their wedges.
  detail::WeldInput weld_input;
  weld_input.position_attributes = vertex_data.position_attributes;
  weld_input.position_attribute_count = vertex_data.position_attribute_count;
  weld_input.attributes = vertex_data.attributes;
  weld_input.attribute_count = vertex_data.attribute_count;
  weld_input.skin_joints = vertex_data.skin_joints;
  weld_input.skin_weights = vertex_data.skin_weights;
  weld_input.influence_count = vertex_data.influence_count;
  weld_input.face_groups = vertex_data.face_groups;
  weld_input.weld = options.weld;
  weld_input.mirror_two_sided = true;
  const detail::PreparedMesh prepared = detail::prepare_mesh(mesh, weld_input);
  AqemPreparation& report = result.preparation;
  report.degenerate_faces = prepared.degenerate_faces;
  report.duplicate_faces = prepared.duplicate_faces;
  report.mirrored_faces = prepared.mirrored_faces;
  report.welded_vertices = prepared.welded_vertices;
  report.seam_vertices = prepared.seam_points;
  report.split_vertices = prepared.split_points;
  report.unreferenced_vertices = prepared.unreferenced_vertices;
  report.face_count = prepared.faces.size() / 3;
  if (report.face_count == 0) return Status::error("faces: every face is degenerate (no face has three distinct positions)");

  std::vector<size_t> targets;
  if (Status status = resolve_targets(report.face_count, mesh.face_count, options, targets); !status) return status;
  PointFrames points(mesh, prepared);
  if (Status status = resolve_frames(points.view(), options, result.frames_used); !status) return status;

  // Steps 3-4: motion features of the welded surface give the point weights of Eq. 6;
  // importance multiplies them.
  const size_t point_count = prepared.point_source.size();
  std::vector<double> weights(point_count, 1.0);
  timer.emplace(seconds.motion_features);
  if (options.use_motion_features) {
    MotionFeatures features;
    if (Status status = compute_motion_features(points.view(), options.motion_features, features); !status)
      return Status::error("motion features of the welded surface: " + status.message);
    for (size_t p = 0; p < point_count; ++p) weights[p] = features.vertex_weights[p];
  }
  if (vertex_data.importance)
    for (size_t p = 0; p < point_count; ++p)
      weights[p] = static_cast<float>(weights[p]) * vertex_data.importance[prepared.point_source[p]];
  result.vertex_weights.assign(mesh.vertex_count, 1.0f);
  for (size_t v = 0; v < mesh.vertex_count; ++v)
    if (prepared.wedge_point[v] >= 0) result.vertex_weights[v] = static_cast<float>(weights[prepared.wedge_point[v]]);

  detail::CarriedData carried;
  carried.locked = vertex_data.locked;
  carried.guarded = vertex_data.guarded;
  carried.attributes = vertex_data.attributes;
  carried.attribute_count = vertex_data.attribute_count;
  carried.position_attributes = vertex_data.position_attributes;
  carried.position_attribute_count = vertex_data.position_attribute_count;
  carried.skin_joints = vertex_data.skin_joints;
  carried.skin_weights = vertex_data.skin_weights;
  carried.influence_count = vertex_data.influence_count;
  detail::EngineOptions engine_options;
  engine_options.check_inversion = options.check_inversion;
  engine_options.fold_limit = options.fold_limit;
  engine_options.max_error = options.max_error;
  engine_options.progress = options.progress;
  engine_options.collapse_passes = true;
  engine_options.record_positions = options.record_positions;
  // The face quadrics need no connectivity: they are summed while the engine builds it (a
  // third thread on two cores; the phases then split the wall time: connectivity is the
  // engine's build, quadrics what the face quadrics take beyond it and the sides' planes).
  // Under a one-thread limit they are summed when asked for, after the build.
  timer.emplace(seconds.connectivity);
  const auto launch = thread_limit() >= 2 ? std::launch::async : std::launch::deferred;
  std::future<FaceQuadrics> face = std::async(launch, [&] {
    return face_quadrics(prepared.faces, points.view(), result.frames_used, options.tip_quadrics);
  });
  CollapseEngine engine(mesh, prepared, carried, engine_options);
  timer.emplace(seconds.quadrics);
  AqemPolicy policy(engine, options, result.frames_used, std::move(weights), face.get());
  points.release();
  timer.reset();
  std::vector<detail::EngineLevel> levels;
  detail::EngineRecord record;
  engine.run(policy, targets, levels, record);
  seconds.ranking = engine.timings().ranking;
  seconds.choosing = engine.timings().choosing;
  seconds.collapsing = engine.timings().collapsing;
  timer.emplace(seconds.levels);
  for (auto& level : levels) result.levels.push_back(to_level(std::move(level)));
  result.collapses.removed = std::move(record.removed);
  result.collapses.kept = std::move(record.kept);
  result.collapses.positions = std::move(record.positions);
  result.collapses.cost = std::move(record.cost);
  result.collapses.error = std::move(record.error);
  timer.reset();
  seconds.levels += engine.timings().levels;
  out = std::move(result);
  return Status::success();
}

}  // namespace animlod
