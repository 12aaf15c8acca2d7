// Queries of the TDAG (Shamir and Pascucci 2001, Sections 2 and 5): random (frame, tolerance)
// queries, incremental queries in time and in resolution, view-dependent tolerances, and the
// three temporal approximation levels.
//
// A cut is a set S of applied collapses closed under the dependencies of the cut's frame. Its
// mesh is kept incrementally: the active vertex nodes, the live input faces with the active
// node at each corner, and per active node the live faces around it. A collapse relabels the
// faces of its two children and removes the faces it kills; a split relabels the faces of the
// node by the child holding each corner's input vertex and brings the killed faces back.
//
// With bounds monotone along dependencies, the tolerance query is the set of collapses whose
// bound is within the tolerance, and an update only needs to look at the fronts: collapses in S
// that nothing in S depends on (may split) and collapses outside S whose dependencies are all
// in S (may collapse), and, in time, only at those whose bound changed between the two frames.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "animlod/tdag.hpp"
#include "tdag_data.hpp"

namespace animlod {

namespace detail {

namespace {

// A set of ids in [0, N) with O(1) insert, erase and membership, iterable.
class IndexedSet {
 public:
  void reset(size_t id_count) {
    items_.clear();
    position_.assign(id_count, -1);
  }
  bool contains(int32_t id) const { return position_[static_cast<size_t>(id)] >= 0; }
  void insert(int32_t id) {
    if (contains(id)) return;
    position_[static_cast<size_t>(id)] = static_cast<int32_t>(items_.size());
    items_.push_back(id);
  }
  void erase(int32_t id) {
    const int32_t at = position_[static_cast<size_t>(id)];
    if (at < 0) return;
    const int32_t last = items_.back();
    items_[static_cast<size_t>(at)] = last;
    position_[static_cast<size_t>(last)] = at;
    items_.pop_back();
    position_[static_cast<size_t>(id)] = -1;
  }
  const std::vector<int32_t>& items() const { return items_; }
  size_t size() const { return items_.size(); }

 private:
  std::vector<int32_t> items_;
  std::vector<int32_t> position_;
};

void erase_value(std::vector<int32_t>& list, int32_t value) {
  auto it = std::find(list.begin(), list.end(), value);
  if (it == list.end()) return;
  *it = list.back();
  list.pop_back();
}

}  // namespace

struct CutState {
  explicit CutState(std::shared_ptr<const TdagData> owned) : data(std::move(owned)), d(data.get()) {}
  CutState(const CutState& other) = default;

  std::shared_ptr<const TdagData> data;
  const TdagData* d;
  bool has_query = false;
  int32_t frame = 0;
  bool view_mode = false;
  double tolerance = 0.0;
  uint16_t code_limit = 0;
  ViewTolerance view;
  int32_t residual_frame = 0;

  std::vector<uint8_t> in_s;             // (C,) collapse applied
  std::vector<int32_t> missing_deps;     // (C,) alive dependencies not in S
  std::vector<int32_t> dependents_in_s;  // (C,) dependents (alive links) in S
  IndexedSet split_front;                // in S, no dependent in S
  IndexedSet collapse_front;             // alive, not in S, every dependency in S
  std::vector<int32_t> slot_of;          // (N,) index of an active node in vertex_nodes, -1
  std::vector<int32_t> vertex_nodes;     // (V',)
  std::vector<float> vertex_residuals;   // (V', 3) at residual_frame
  std::vector<int32_t> corner_nodes;     // (M, 3) active node at each corner of a live face
  std::vector<int32_t> face_slot;        // (M,) index in face_ids, -1
  std::vector<int32_t> face_ids;         // (M',) live faces
  std::vector<std::vector<int32_t>> faces_of;  // (N,) live faces around an active node
  size_t splits = 0, collapses = 0;
  // A node a split or collapse found inactive (-1: none): the dependencies do not order the
  // collapses after their children, which the reader refuses (tdag_io.cpp); kept as a cheap
  // guard so that such a TDAG gives an error instead of a write outside the arrays.
  int32_t inactive_node = -1;
  std::vector<int32_t> stack, queue, anc;  // scratch
  std::vector<int8_t> closure;             // scratch: -1 unknown, 0 no, 1 yes, 2 visiting

  int32_t node_of(size_t c) const { return d->vertex_count + static_cast<int32_t>(c); }
  size_t collapse_of(int32_t node) const { return static_cast<size_t>(node - d->vertex_count); }
  bool alive(size_t c) const { return d->collapse_alive(c, frame); }

  template <typename Visit>
  void for_each_dependency(size_t c, Visit&& visit) const {
    for (int32_t link = d->dep_offsets[c]; link < d->dep_offsets[c + 1]; ++link)
      if (d->link_alive(static_cast<size_t>(link), frame)) visit(collapse_of(d->dep_nodes[static_cast<size_t>(link)]));
  }
  template <typename Visit>
  void for_each_dependent(size_t c, Visit&& visit) const {
    for (int32_t i = d->dependent_offsets[c]; i < d->dependent_offsets[c + 1]; ++i)
      if (d->link_alive(static_cast<size_t>(d->dependent_links[static_cast<size_t>(i)]), frame))
        visit(collapse_of(d->dependent_nodes[static_cast<size_t>(i)]));
  }

  const float* residual_of(int32_t node, int32_t at) const {
    return &d->residuals[(static_cast<size_t>(at) * static_cast<size_t>(d->vertex_count) +
                          static_cast<size_t>(d->representative[static_cast<size_t>(node)])) * 3];
  }

  // Whether collapse c may stand for its input vertices: its bound is within the tolerance.
  bool meets(size_t c) const {
    if (!alive(c)) return false;
    const uint16_t code = d->error_code(c, frame);
    if (!view_mode) return code <= code_limit;
    const double bound = decode_error(code, d->scale);
    float p[3];
    apply_affine(&d->maps[static_cast<size_t>(frame) * 12], residual_of(node_of(c), frame), 1, p);
    const double dx = p[0] - view.camera[0], dy = p[1] - view.camera[1], dz = p[2] - view.camera[2];
    const double distance = std::sqrt(dx * dx + dy * dy + dz * dz);
    return bound <= view.pixels * std::max(distance - bound, 0.0) / view.focal_pixels;
  }

  // ---- the mesh ----
  void activate_vertex(int32_t node) {
    slot_of[static_cast<size_t>(node)] = static_cast<int32_t>(vertex_nodes.size());
    vertex_nodes.push_back(node);
    const float* r = residual_of(node, residual_frame);
    vertex_residuals.insert(vertex_residuals.end(), r, r + 3);
  }
  void deactivate_vertex(int32_t node) {
    if (slot_of[static_cast<size_t>(node)] < 0) {
      inactive_node = node;
      return;
    }
    const auto slot = static_cast<size_t>(slot_of[static_cast<size_t>(node)]);
    const size_t last = vertex_nodes.size() - 1;
    const int32_t moved = vertex_nodes[last];
    vertex_nodes[slot] = moved;
    std::copy_n(&vertex_residuals[last * 3], 3, &vertex_residuals[slot * 3]);
    slot_of[static_cast<size_t>(moved)] = static_cast<int32_t>(slot);
    vertex_nodes.pop_back();
    vertex_residuals.resize(last * 3);
    slot_of[static_cast<size_t>(node)] = -1;
  }
  void activate_face(int32_t face) {
    face_slot[static_cast<size_t>(face)] = static_cast<int32_t>(face_ids.size());
    face_ids.push_back(face);
    for (int k = 0; k < 3; ++k)
      faces_of[static_cast<size_t>(corner_nodes[3 * static_cast<size_t>(face) + static_cast<size_t>(k)])].push_back(face);
  }
  void deactivate_face(int32_t face) {
    for (int k = 0; k < 3; ++k)
      erase_value(faces_of[static_cast<size_t>(corner_nodes[3 * static_cast<size_t>(face) + static_cast<size_t>(k)])], face);
    const auto slot = static_cast<size_t>(face_slot[static_cast<size_t>(face)]);
    const int32_t moved = face_ids.back();
    face_ids[slot] = moved;
    face_slot[static_cast<size_t>(moved)] = static_cast<int32_t>(slot);
    face_ids.pop_back();
    face_slot[static_cast<size_t>(face)] = -1;
  }
  // The active node standing for input vertex `vertex` (walks up the hierarchy of the frame).
  int32_t active_ancestor(int32_t vertex) const {
    int32_t x = vertex;
    while (x >= 0 && slot_of[static_cast<size_t>(x)] < 0) x = d->parent_at(x, frame);
    return x;
  }

  // The child of a split node (kept or removed, both active) that stands for input vertex
  // `vertex`: O(1) with the leaf ranges of a static structure, else a walk up the hierarchy.
  int32_t child_holding(int32_t vertex, int32_t kept, int32_t removed) const {
    if (d->leaf_range.empty()) return active_ancestor(vertex);
    const int32_t position = d->leaf_position[static_cast<size_t>(vertex)];
    const auto& range = d->leaf_range[static_cast<size_t>(kept)];
    return range[0] <= position && position < range[1] ? kept : removed;
  }

  // ---- collapse and split of one node; counters and fronts ----
  void collapse(size_t c) {
    const int32_t node = node_of(c), kept = d->kept_child[c], removed = d->removed_child[c];
    for (int32_t face : d->killed[c])
      if (face >= 0 && face_slot[static_cast<size_t>(face)] >= 0) deactivate_face(face);
    for (const int32_t child : {kept, removed}) {
      auto& list = faces_of[static_cast<size_t>(child)];
      for (int32_t face : list) {
        for (size_t k = 0; k < 3; ++k)
          if (corner_nodes[3 * static_cast<size_t>(face) + k] == child) corner_nodes[3 * static_cast<size_t>(face) + k] = node;
        faces_of[static_cast<size_t>(node)].push_back(face);
      }
      list.clear();
    }
    deactivate_vertex(kept);
    deactivate_vertex(removed);
    activate_vertex(node);
    in_s[c] = 1;
    ++collapses;
    for_each_dependent(c, [&](size_t m) {
      if (--missing_deps[m] == 0 && !in_s[m] && alive(m)) collapse_front.insert(static_cast<int32_t>(m));
    });
    for_each_dependency(c, [&](size_t k) {
      if (dependents_in_s[k]++ == 0) split_front.erase(static_cast<int32_t>(k));
    });
    collapse_front.erase(static_cast<int32_t>(c));
    if (dependents_in_s[c] == 0) split_front.insert(static_cast<int32_t>(c));
  }

  void split(size_t c) {
    const int32_t node = node_of(c), kept = d->kept_child[c], removed = d->removed_child[c];
    deactivate_vertex(node);
    activate_vertex(kept);
    activate_vertex(removed);
    auto list = std::move(faces_of[static_cast<size_t>(node)]);
    faces_of[static_cast<size_t>(node)].clear();
    for (int32_t face : list)
      for (size_t k = 0; k < 3; ++k) {
        const size_t corner = 3 * static_cast<size_t>(face) + k;
        if (corner_nodes[corner] != node) continue;
        const int32_t child = child_holding(d->faces[corner], kept, removed);
        corner_nodes[corner] = child;
        faces_of[static_cast<size_t>(child)].push_back(face);
      }
    for (int32_t face : d->killed[c]) {
      if (face < 0 || face_slot[static_cast<size_t>(face)] >= 0) continue;
      for (size_t k = 0; k < 3; ++k) {
        const size_t corner = 3 * static_cast<size_t>(face) + k;
        corner_nodes[corner] = active_ancestor(d->faces[corner]);
      }
      activate_face(face);
    }
    in_s[c] = 0;
    ++splits;
    for_each_dependent(c, [&](size_t m) {
      if (missing_deps[m]++ == 0) collapse_front.erase(static_cast<int32_t>(m));
    });
    for_each_dependency(c, [&](size_t k) {
      if (--dependents_in_s[k] == 0) split_front.insert(static_cast<int32_t>(k));
    });
    split_front.erase(static_cast<int32_t>(c));
    if (alive(c) && missing_deps[c] == 0) collapse_front.insert(static_cast<int32_t>(c));
  }

  // Splits c after splitting everything in S that depends on it.
  void force_split(size_t c) {
    stack.assign(1, static_cast<int32_t>(c));
    while (!stack.empty()) {
      const auto x = static_cast<size_t>(stack.back());
      if (!in_s[x]) {
        stack.pop_back();
        continue;
      }
      bool pushed = false;
      if (dependents_in_s[x] > 0)
        for_each_dependent(x, [&](size_t m) {
          if (!pushed && in_s[m]) {
            stack.push_back(static_cast<int32_t>(m));
            pushed = true;
          }
        });
      if (pushed) continue;
      stack.pop_back();
      split(x);
    }
  }

  // Collapses c after collapsing every dependency of it not in S.
  void force_collapse(size_t c) {
    stack.assign(1, static_cast<int32_t>(c));
    while (!stack.empty()) {
      const auto x = static_cast<size_t>(stack.back());
      if (in_s[x]) {
        stack.pop_back();
        continue;
      }
      bool pushed = false;
      if (missing_deps[x] > 0)
        for_each_dependency(x, [&](size_t k) {
          if (!pushed && !in_s[k]) {
            stack.push_back(static_cast<int32_t>(k));
            pushed = true;
          }
        });
      if (pushed) continue;
      stack.pop_back();
      collapse(x);
    }
  }

  // The largest dependency-closed set of collapses that all meet their tolerance (memoised
  // depth-first search; with bounds monotone along dependencies this is simply the set of
  // collapses within the tolerance). Leaves 1 in closure[c] for members.
  void compute_closure() {
    const size_t collapse_count = d->collapse_count();
    closure.assign(collapse_count, -1);
    for (size_t root = 0; root < collapse_count; ++root) {
      if (closure[root] >= 0) continue;
      stack.assign(1, static_cast<int32_t>(root));
      while (!stack.empty()) {
        const auto x = static_cast<size_t>(stack.back());
        if (closure[x] == 0 || closure[x] == 1) {
          stack.pop_back();
          continue;
        }
        if (closure[x] == -1) {
          if (!meets(x)) {
            closure[x] = 0;
            stack.pop_back();
            continue;
          }
          closure[x] = 2;
          for_each_dependency(x, [&](size_t k) {
            if (closure[k] == -1) stack.push_back(static_cast<int32_t>(k));
          });
          continue;
        }
        // closure[x] == 2: every dependency is decided (or on the stack in a cycle: refused).
        bool all = true;
        for_each_dependency(x, [&](size_t k) { all &= closure[k] == 1; });
        closure[x] = all ? 1 : 0;
        stack.pop_back();
      }
    }
  }

  // A fresh cut at `frame` from the closure.
  void rebuild() {
    const size_t collapse_count = d->collapse_count(), node_count = d->node_count(), face_count = d->face_count();
    compute_closure();
    in_s.assign(collapse_count, 0);
    for (size_t c = 0; c < collapse_count; ++c) in_s[c] = closure[c] == 1;
    missing_deps.assign(collapse_count, 0);
    dependents_in_s.assign(collapse_count, 0);
    for (size_t c = 0; c < collapse_count; ++c) {
      if (!alive(c)) continue;
      for_each_dependency(c, [&](size_t k) {
        if (!in_s[k]) ++missing_deps[c];
        if (in_s[c]) ++dependents_in_s[k];
      });
    }
    split_front.reset(collapse_count);
    collapse_front.reset(collapse_count);
    for (size_t c = 0; c < collapse_count; ++c) {
      if (in_s[c] && dependents_in_s[c] == 0) split_front.insert(static_cast<int32_t>(c));
      if (!in_s[c] && alive(c) && missing_deps[c] == 0) collapse_front.insert(static_cast<int32_t>(c));
    }
    // The active node of every node: parents have larger ids, so one pass from the top.
    anc.assign(node_count, -1);
    for (size_t x = node_count; x-- > 0;) {
      const int32_t parent = d->parent_at(static_cast<int32_t>(x), frame);
      anc[x] = parent >= 0 && in_s[collapse_of(parent)] ? anc[static_cast<size_t>(parent)] : static_cast<int32_t>(x);
    }
    slot_of.assign(node_count, -1);
    vertex_nodes.clear();
    vertex_residuals.clear();
    if (faces_of.size() != node_count) faces_of.assign(node_count, {});
    for (auto& list : faces_of) list.clear();
    for (size_t v = 0; v < static_cast<size_t>(d->vertex_count); ++v)
      if (slot_of[static_cast<size_t>(anc[v])] < 0) activate_vertex(anc[v]);
    corner_nodes.assign(3 * face_count, -1);
    face_slot.assign(face_count, -1);
    face_ids.clear();
    for (size_t f = 0; f < face_count; ++f) {
      int32_t* corners = &corner_nodes[3 * f];
      for (size_t k = 0; k < 3; ++k) corners[k] = anc[static_cast<size_t>(d->faces[3 * f + k])];
      if (corners[0] != corners[1] && corners[1] != corners[2] && corners[0] != corners[2])
        activate_face(static_cast<int32_t>(f));
    }
    splits = collapses = 0;
  }

  // Splits and collapses to reach the closure (view-dependent updates).
  void transition_to_closure() {
    compute_closure();
    const size_t collapse_count = d->collapse_count();
    for (size_t c = 0; c < collapse_count; ++c)
      if (in_s[c] && closure[c] != 1) force_split(c);
    for (size_t c = 0; c < collapse_count; ++c)
      if (!in_s[c] && closure[c] == 1) force_collapse(c);
  }

  // Front updates from the collapses in `queue` until no front collapse can change (tolerance mode).
  void settle() {
    for (size_t i = 0; i < queue.size(); ++i) {
      const auto c = static_cast<size_t>(queue[i]);
      if (in_s[c]) {
        if (dependents_in_s[c] != 0 || meets(c)) continue;
        split(c);
        for_each_dependency(c, [&](size_t k) { queue.push_back(static_cast<int32_t>(k)); });
      } else {
        if (missing_deps[c] != 0 || !alive(c) || !meets(c)) continue;
        collapse(c);
        for_each_dependent(c, [&](size_t m) { queue.push_back(static_cast<int32_t>(m)); });
      }
    }
    queue.clear();
  }

  void queue_fronts() {
    queue.assign(split_front.items().begin(), split_front.items().end());
    queue.insert(queue.end(), collapse_front.items().begin(), collapse_front.items().end());
  }

  // Moves the cut to `target` (see TdagCut::advance).
  void move_to(int32_t target) {
    splits = collapses = 0;
    const int32_t low = std::min(frame, target), high = std::max(frame, target);
    const size_t collapse_count = d->collapse_count();
    if (!d->static_structure) {
      // Collapses whose structure differs somewhere between the two frames leave S first.
      const auto begin = static_cast<size_t>(d->event_offsets[static_cast<size_t>(low) + 1]);
      const auto end = static_cast<size_t>(d->event_offsets[static_cast<size_t>(high) + 1]);
      if (4 * (end - begin) > collapse_count) {
        frame = target;
        rebuild();
        return;
      }
      for (size_t i = begin; i < end; ++i) force_split(collapse_of(d->event_nodes[i]));
      frame = target;
      for (size_t i = begin; i < end; ++i) {
        const size_t c = collapse_of(d->event_nodes[i]);
        missing_deps[c] = 0;
        dependents_in_s[c] = 0;
        for_each_dependency(c, [&](size_t k) { missing_deps[c] += in_s[k] ? 0 : 1; });
        for_each_dependent(c, [&](size_t m) { dependents_in_s[c] += in_s[m] ? 1 : 0; });
        split_front.erase(static_cast<int32_t>(c));
        if (alive(c) && missing_deps[c] == 0) collapse_front.insert(static_cast<int32_t>(c));
        else collapse_front.erase(static_cast<int32_t>(c));
      }
    }
    frame = target;
    if (view_mode) {
      transition_to_closure();
      return;
    }
    // Only collapses whose bound changed between the frames can cross the tolerance; when they
    // are more than the fronts, look at the fronts instead.
    const auto begin = static_cast<size_t>(d->change_offsets[static_cast<size_t>(low) + 1]);
    const auto end = static_cast<size_t>(d->change_offsets[static_cast<size_t>(high) + 1]);
    if (end - begin < split_front.size() + collapse_front.size()) {
      queue.clear();
      for (size_t i = begin; i < end; ++i) queue.push_back(static_cast<int32_t>(collapse_of(d->change_nodes[i])));
    } else {
      queue_fronts();
    }
    settle();
  }

  void refresh_residuals(int32_t at) {
    residual_frame = at;
    for (size_t slot = 0; slot < vertex_nodes.size(); ++slot)
      std::copy_n(residual_of(vertex_nodes[slot], at), 3, &vertex_residuals[slot * 3]);
  }

  // The mesh with the affine map of `at` and the residuals of `residuals_at` (the cached ones
  // when that is residual_frame).
  void emit(int32_t at, int32_t residuals_at, TdagMesh& out) const {
    out.frame = at;
    out.cut_frame = frame;
    out.residual_frame = residuals_at;
    out.positions.resize(vertex_residuals.size());
    const double* map = &d->maps[static_cast<size_t>(at) * 12];
    if (residuals_at == residual_frame) {
      apply_affine(map, vertex_residuals.data(), vertex_nodes.size(), out.positions.data());
    } else {
      for (size_t slot = 0; slot < vertex_nodes.size(); ++slot)
        apply_affine(map, residual_of(vertex_nodes[slot], residuals_at), 1, &out.positions[3 * slot]);
    }
    out.faces.resize(face_ids.size() * 3);
    for (size_t i = 0; i < face_ids.size(); ++i)
      for (size_t k = 0; k < 3; ++k)
        out.faces[3 * i + k] = slot_of[static_cast<size_t>(corner_nodes[3 * static_cast<size_t>(face_ids[i]) + k])];
    // A two-sided face's back, turned over on the same vertices, after the others (as AQEM's levels).
    if (!d->two_sided.empty())
      for (int32_t face : face_ids) {
        if (!d->two_sided[static_cast<size_t>(face)]) continue;
        for (size_t k : {0, 2, 1})
          out.faces.push_back(slot_of[static_cast<size_t>(corner_nodes[3 * static_cast<size_t>(face) + k])]);
      }
    out.nodes = vertex_nodes;
    out.error_bound = error_bound();
  }

  double error_bound() const {
    uint16_t largest = 0;
    for (int32_t node : vertex_nodes)
      if (node >= d->vertex_count) largest = std::max(largest, d->error_code(collapse_of(node), frame));
    return decode_error(largest, d->scale);
  }
};

}  // namespace detail

namespace {

Status check_frame(const detail::TdagData* d, int32_t frame) {
  if (!d) return Status::error("TemporalDag: empty (build or load one first)");
  if (frame < 0 || frame >= d->frame_count)
    return Status::error("frame: " + std::to_string(frame) + " outside [0, " + std::to_string(d->frame_count) + ")");
  return Status::success();
}

Status check_tolerance(double tolerance) {
  if (std::isnan(tolerance) || tolerance < 0.0)
    return Status::error("tolerance: must be >= 0, got " + std::to_string(tolerance));
  return Status::success();
}

Status check_view(const ViewTolerance& view) {
  for (double c : view.camera)
    if (!std::isfinite(c)) return Status::error("camera: position must be finite");
  if (!(view.pixels > 0.0) || !std::isfinite(view.pixels))
    return Status::error("pixels: must be > 0 and finite, got " + std::to_string(view.pixels));
  if (!(view.focal_pixels > 0.0) || !std::isfinite(view.focal_pixels))
    return Status::error("focal_pixels: must be > 0 and finite, got " + std::to_string(view.focal_pixels));
  return Status::success();
}

// After an update: an error naming the node when the TDAG proved inconsistent (see
// CutState::inactive_node); the cut is then rebuilt from scratch at its frame, so that it stays a
// valid mesh of the collapses it holds.
Status check_consistent(detail::CutState& s, const char* what) {
  if (s.inactive_node < 0) return Status::success();
  const int32_t node = s.inactive_node;
  s.rebuild();
  s.inactive_node = -1;
  return Status::error(std::string(what) + ": node " + std::to_string(node) +
                       " was split or merged while not in the cut: the TDAG's dependencies do not order its "
                       "collapses after their children (a damaged TDAG)");
}

}  // namespace

TdagCut::TdagCut(const TemporalDag& dag) : state_(std::make_unique<detail::CutState>(dag.data_)) {}
TdagCut::~TdagCut() = default;
TdagCut::TdagCut(TdagCut&&) noexcept = default;
TdagCut& TdagCut::operator=(TdagCut&&) noexcept = default;
TdagCut::TdagCut(const TdagCut& other) : state_(std::make_unique<detail::CutState>(*other.state_)) {}
TdagCut& TdagCut::operator=(const TdagCut& other) {
  if (this != &other) state_ = std::make_unique<detail::CutState>(*other.state_);
  return *this;
}

Status TdagCut::query(int32_t frame, double tolerance) {
  detail::CutState& s = *state_;
  if (Status status = check_frame(s.d, frame); !status) return status;
  if (Status status = check_tolerance(tolerance); !status) return status;
  s.frame = frame;
  s.residual_frame = frame;
  s.view_mode = false;
  s.tolerance = tolerance;
  s.code_limit = detail::largest_code_within(tolerance, s.d->scale);
  s.rebuild();
  s.has_query = true;
  return Status::success();
}

Status TdagCut::query_view(int32_t frame, const ViewTolerance& view) {
  detail::CutState& s = *state_;
  if (Status status = check_frame(s.d, frame); !status) return status;
  if (Status status = check_view(view); !status) return status;
  s.frame = frame;
  s.residual_frame = frame;
  s.view_mode = true;
  s.view = view;
  s.rebuild();
  s.has_query = true;
  return Status::success();
}

Status TdagCut::advance(int32_t frame) {
  detail::CutState& s = *state_;
  if (Status status = check_frame(s.d, frame); !status) return status;
  if (!s.has_query) return Status::error("advance: no query yet (call query or query_view first)");
  if (frame == s.frame) {
    s.splits = s.collapses = 0;
    return Status::success();
  }
  s.move_to(frame);
  return check_consistent(s, "advance");
}

Status TdagCut::refine(double tolerance) {
  detail::CutState& s = *state_;
  if (!s.has_query) return Status::error("refine: no query yet (call query or query_view first)");
  if (Status status = check_tolerance(tolerance); !status) return status;
  s.view_mode = false;
  s.tolerance = tolerance;
  s.code_limit = detail::largest_code_within(tolerance, s.d->scale);
  s.splits = s.collapses = 0;
  s.queue_fronts();
  s.settle();
  return check_consistent(s, "refine");
}

Status TdagCut::refine_view(const ViewTolerance& view) {
  detail::CutState& s = *state_;
  if (!s.has_query) return Status::error("refine_view: no query yet (call query or query_view first)");
  if (Status status = check_view(view); !status) return status;
  s.view_mode = true;
  s.view = view;
  s.splits = s.collapses = 0;
  s.transition_to_closure();
  return check_consistent(s, "refine_view");
}

Status TdagCut::approximate(int32_t frame, ApproximationLevel level, TdagMesh& out) {
  detail::CutState& s = *state_;
  if (Status status = check_frame(s.d, frame); !status) return status;
  if (!s.has_query) return Status::error("approximate: no query yet (call query or query_view first)");
  switch (level) {
    case ApproximationLevel::full:
      if (frame != s.frame) s.move_to(frame);
      if (Status status = check_consistent(s, "approximate"); !status) return status;
      s.refresh_residuals(frame);
      break;
    case ApproximationLevel::residual:
      s.refresh_residuals(frame);
      break;
    case ApproximationLevel::affine:
      break;
    default:
      return Status::error("level: " + std::to_string(static_cast<int>(level)) + " is not 1, 2 or 3");
  }
  s.emit(frame, s.residual_frame, out);
  return Status::success();
}

void TdagCut::mesh(TdagMesh& out) const { state_->emit(state_->frame, state_->frame, out); }

void TdagCut::input_vertex_map(std::vector<int32_t>& out) const {
  const detail::CutState& s = *state_;
  const size_t node_count = s.d->node_count();
  std::vector<int32_t> slot(node_count, -1);
  for (size_t x = node_count; x-- > 0;) {
    if (s.slot_of[x] >= 0) {
      slot[x] = s.slot_of[x];
      continue;
    }
    const int32_t parent = s.d->parent_at(static_cast<int32_t>(x), s.frame);
    slot[x] = parent >= 0 ? slot[static_cast<size_t>(parent)] : -1;
  }
  out.assign(slot.begin(), slot.begin() + s.d->vertex_count);
}

int32_t TdagCut::frame() const { return state_->frame; }
double TdagCut::tolerance() const {
  return state_->view_mode ? std::numeric_limits<double>::quiet_NaN() : state_->tolerance;
}
bool TdagCut::has_query() const { return state_->has_query; }
size_t TdagCut::active_vertex_count() const { return state_->vertex_nodes.size(); }
size_t TdagCut::active_face_count() const { return state_->face_ids.size(); }
double TdagCut::error_bound() const { return state_->error_bound(); }
size_t TdagCut::last_split_count() const { return state_->splits; }
size_t TdagCut::last_collapse_count() const { return state_->collapses; }

}  // namespace animlod
