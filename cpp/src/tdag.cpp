// The TDAG object (Shamir and Pascucci 2001, Section 2): accessors over the stored fields, and
// the links derived from them (parents, dependents, the frames at which fields change).
#include "animlod/tdag.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <string>

#include "tdag_data.hpp"

namespace animlod {

namespace detail {

namespace {

std::string collapse_name(size_t c) { return "collapse " + std::to_string(c); }

// Every range of `tag` inside [0, frame_count).
bool tag_in_range(const TimeTag& tag, int32_t frame_count) {
  return tag.empty() || (tag.ranges().front().birth >= 0 && tag.ranges().back().death <= frame_count);
}

// Sorted, de-duplicated per-frame lists (CSR over frames 0 .. F-1) from (frame, node) pairs.
void frame_lists(std::vector<std::pair<int32_t, int32_t>>& pairs, int32_t frame_count, std::vector<int32_t>& offsets,
                 std::vector<int32_t>& nodes) {
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  offsets.assign(static_cast<size_t>(frame_count) + 1, 0);
  nodes.clear();
  nodes.reserve(pairs.size());
  for (const auto& [frame, node] : pairs) {
    offsets[static_cast<size_t>(frame) + 1] += 1;
    nodes.push_back(node);
  }
  for (size_t f = 0; f < static_cast<size_t>(frame_count); ++f) offsets[f + 1] += offsets[f];
}

}  // namespace

Status derive_links(TdagData& data) {
  const int32_t vertex_count = data.vertex_count, frame_count = data.frame_count;
  const size_t collapse_count = data.collapse_count();
  const auto node_count = static_cast<int64_t>(data.node_count());
  if (data.removed_child.size() != collapse_count || data.killed.size() != collapse_count ||
      data.alive.size() != collapse_count || data.dep_offsets.size() != collapse_count + 1 ||
      data.dep_tags.size() != data.dep_nodes.size())
    return Status::error("collapse fields of different lengths");
  if (data.codes_by_frame.size() != static_cast<size_t>(frame_count) * collapse_count)
    return Status::error("error codes: " + std::to_string(data.codes_by_frame.size()) + " for " +
                         std::to_string(frame_count) + " frames of " + std::to_string(collapse_count) + " collapses");
  const auto face_count = static_cast<int32_t>(data.face_count());
  for (size_t v = 0; v < data.input_points.size(); ++v)
    if (data.input_points[v] < -1 || data.input_points[v] >= vertex_count)
      return Status::error("input vertex " + std::to_string(v) + ": vertex " + std::to_string(data.input_points[v]) +
                           " outside [0, " + std::to_string(vertex_count) + ")");
  if (!data.two_sided.empty() && data.two_sided.size() != data.face_count())
    return Status::error("two-sided flags: " + std::to_string(data.two_sided.size()) + " for " +
                         std::to_string(data.face_count()) + " faces");
  for (size_t i = 0; i < data.faces.size(); ++i)
    if (data.faces[i] < 0 || data.faces[i] >= vertex_count)
      return Status::error("face " + std::to_string(i / 3) + ": vertex index " + std::to_string(data.faces[i]) +
                           " outside [0, " + std::to_string(vertex_count) + ")");

  // Children, killed faces, tags; the representative of each node.
  data.representative.resize(static_cast<size_t>(node_count));
  for (int32_t v = 0; v < vertex_count; ++v) data.representative[static_cast<size_t>(v)] = v;
  bool static_structure = true;
  for (size_t c = 0; c < collapse_count; ++c) {
    const int64_t node = vertex_count + static_cast<int64_t>(c);
    const int32_t kept = data.kept_child[c], removed = data.removed_child[c];
    if (kept < 0 || removed < 0 || kept >= node || removed >= node || kept == removed)
      return Status::error(collapse_name(c) + ": children (" + std::to_string(kept) + ", " + std::to_string(removed) +
                           ") must be distinct nodes below " + std::to_string(node));
    for (int32_t face : data.killed[c])
      if (face < -1 || face >= face_count)
        return Status::error(collapse_name(c) + ": removed face " + std::to_string(face) + " outside [0, " +
                             std::to_string(face_count) + ")");
    if (!tag_in_range(data.alive[c], frame_count))
      return Status::error(collapse_name(c) + ": alive outside [0, " + std::to_string(frame_count) + ")");
    static_structure &= data.alive[c] == TimeTag(0, frame_count);
    data.representative[static_cast<size_t>(node)] = data.representative[static_cast<size_t>(kept)];
    if (data.dep_offsets[c] > data.dep_offsets[c + 1]) return Status::error(collapse_name(c) + ": negative field length");
  }
  if (data.dep_offsets.front() != 0 || static_cast<size_t>(data.dep_offsets.back()) != data.dep_nodes.size())
    return Status::error("field offsets do not match the stored values");
  for (size_t c = 0; c < collapse_count; ++c) {
    for (int32_t link = data.dep_offsets[c]; link < data.dep_offsets[c + 1]; ++link) {
      const int32_t d = data.dep_nodes[static_cast<size_t>(link)];
      if (d < vertex_count || d >= node_count || d == vertex_count + static_cast<int64_t>(c))
        return Status::error(collapse_name(c) + ": dependency " + std::to_string(d) + " is not another collapse");
      const TimeTag& tag = data.dep_tags[static_cast<size_t>(link)];
      if (!tag_in_range(tag, frame_count))
        return Status::error(collapse_name(c) + ": dependency tag outside [0, " + std::to_string(frame_count) + ")");
      static_structure &= tag == TimeTag(0, frame_count);
    }
  }
  data.static_structure = static_structure;

  // Parents: every collapse that has the node as a child; at most one alive per frame.
  data.parent_offsets.assign(static_cast<size_t>(node_count) + 1, 0);
  for (size_t c = 0; c < collapse_count; ++c) {
    data.parent_offsets[static_cast<size_t>(data.kept_child[c]) + 1] += 1;
    data.parent_offsets[static_cast<size_t>(data.removed_child[c]) + 1] += 1;
  }
  for (size_t n = 0; n < static_cast<size_t>(node_count); ++n) data.parent_offsets[n + 1] += data.parent_offsets[n];
  data.parent_nodes.assign(static_cast<size_t>(data.parent_offsets.back()), -1);
  {
    std::vector<int32_t> fill(data.parent_offsets.begin(), data.parent_offsets.end() - 1);
    for (size_t c = 0; c < collapse_count; ++c) {
      const auto node = static_cast<int32_t>(vertex_count + static_cast<int64_t>(c));
      data.parent_nodes[static_cast<size_t>(fill[static_cast<size_t>(data.kept_child[c])]++)] = node;
      data.parent_nodes[static_cast<size_t>(fill[static_cast<size_t>(data.removed_child[c])]++)] = node;
    }
  }
  for (size_t n = 0; n < static_cast<size_t>(node_count); ++n) {
    const int32_t begin = data.parent_offsets[n], end = data.parent_offsets[n + 1];
    if (end - begin < 2) continue;
    TimeTag seen;
    for (int32_t i = begin; i < end; ++i) {
      const TimeTag& tag = data.alive[static_cast<size_t>(data.parent_nodes[static_cast<size_t>(i)] - vertex_count)];
      if (!seen.intersected(tag).empty())
        return Status::error("node " + std::to_string(n) + ": merged by two collapses in the same frame");
      seen = seen.united(tag);
    }
  }

  // Leaf ranges of a static forest: children are visited kept first, leaves numbered in order.
  data.leaf_position.clear();
  data.leaf_range.clear();
  if (static_structure) {
    data.leaf_position.assign(static_cast<size_t>(vertex_count), -1);
    data.leaf_range.assign(static_cast<size_t>(node_count), {0, 0});
    int32_t next = 0;
    std::vector<std::pair<int32_t, bool>> stack;  // (node, children done)
    for (size_t root = static_cast<size_t>(node_count); root-- > 0;) {
      if (data.parent_offsets[root + 1] > data.parent_offsets[root]) continue;  // not a root
      stack.assign(1, {static_cast<int32_t>(root), false});
      while (!stack.empty()) {
        auto [node, done] = stack.back();
        stack.pop_back();
        auto& range = data.leaf_range[static_cast<size_t>(node)];
        if (node < vertex_count) {
          data.leaf_position[static_cast<size_t>(node)] = next;
          range = {next, next + 1};
          ++next;
          continue;
        }
        const size_t c = static_cast<size_t>(node - vertex_count);
        if (done) {
          range = {data.leaf_range[static_cast<size_t>(data.kept_child[c])][0],
                   data.leaf_range[static_cast<size_t>(data.removed_child[c])][1]};
          continue;
        }
        stack.push_back({node, true});
        stack.push_back({data.removed_child[c], false});
        stack.push_back({data.kept_child[c], false});
      }
    }
  }

  // Dependents: the reverse links, with the index of the link for its tag.
  data.dependent_offsets.assign(collapse_count + 1, 0);
  for (int32_t d : data.dep_nodes) data.dependent_offsets[static_cast<size_t>(d - vertex_count) + 1] += 1;
  for (size_t c = 0; c < collapse_count; ++c) data.dependent_offsets[c + 1] += data.dependent_offsets[c];
  data.dependent_nodes.assign(data.dep_nodes.size(), -1);
  data.dependent_links.assign(data.dep_nodes.size(), -1);
  {
    std::vector<int32_t> fill(data.dependent_offsets.begin(), data.dependent_offsets.end() - 1);
    for (size_t c = 0; c < collapse_count; ++c)
      for (int32_t link = data.dep_offsets[c]; link < data.dep_offsets[c + 1]; ++link) {
        const auto slot = static_cast<size_t>(fill[static_cast<size_t>(data.dep_nodes[static_cast<size_t>(link)] - vertex_count)]++);
        data.dependent_nodes[slot] = static_cast<int32_t>(vertex_count + static_cast<int64_t>(c));
        data.dependent_links[slot] = link;
      }
  }

  // Frames at which a collapse's structure (alive, links) changes.
  std::vector<std::pair<int32_t, int32_t>> events;
  auto boundaries = [&](const TimeTag& tag, int32_t node) {
    for (const FrameRange& r : tag.ranges()) {
      if (r.birth > 0) events.emplace_back(r.birth, node);
      if (r.death < frame_count) events.emplace_back(r.death, node);
    }
  };
  if (!static_structure) {
    for (size_t c = 0; c < collapse_count; ++c) {
      const auto node = static_cast<int32_t>(vertex_count + static_cast<int64_t>(c));
      boundaries(data.alive[c], node);
      for (int32_t link = data.dep_offsets[c]; link < data.dep_offsets[c + 1]; ++link) {
        const size_t before = events.size();
        boundaries(data.dep_tags[static_cast<size_t>(link)], node);
        for (size_t i = before, end = events.size(); i < end; ++i) {
          const int32_t frame = events[i].first;  // a copy: emplace_back may reallocate
          events.emplace_back(frame, data.dep_nodes[static_cast<size_t>(link)]);
        }
      }
    }
  }
  frame_lists(events, frame_count, data.event_offsets, data.event_nodes);
  // ... or its structure or error code: a frame's events and the codes that differ from the
  // frame before, both in node order.
  data.change_offsets.assign(static_cast<size_t>(frame_count) + 1, 0);
  data.change_nodes.clear();
  std::vector<int32_t> recoded;
  for (size_t t = 1; t < static_cast<size_t>(frame_count); ++t) {
    const uint16_t* now = data.codes_by_frame.data() + t * collapse_count;
    const uint16_t* before = now - collapse_count;
    recoded.clear();
    for (size_t c = 0; c < collapse_count; ++c)
      if (now[c] != before[c]) recoded.push_back(static_cast<int32_t>(vertex_count + static_cast<int64_t>(c)));
    std::set_union(recoded.begin(), recoded.end(), data.event_nodes.begin() + data.event_offsets[t],
                   data.event_nodes.begin() + data.event_offsets[t + 1], std::back_inserter(data.change_nodes));
    data.change_offsets[t + 1] = static_cast<int32_t>(data.change_nodes.size());
  }
  return Status::success();
}

}  // namespace detail

TemporalDag::TemporalDag() = default;
TemporalDag::~TemporalDag() = default;
TemporalDag::TemporalDag(const TemporalDag&) = default;
TemporalDag& TemporalDag::operator=(const TemporalDag&) = default;

bool TemporalDag::empty() const { return !data_; }
size_t TemporalDag::frame_count() const { return data_ ? static_cast<size_t>(data_->frame_count) : 0; }
size_t TemporalDag::vertex_count() const { return data_ ? static_cast<size_t>(data_->vertex_count) : 0; }
size_t TemporalDag::face_count() const { return data_ ? data_->face_count() : 0; }
size_t TemporalDag::collapse_count() const { return data_ ? data_->collapse_count() : 0; }
size_t TemporalDag::node_count() const { return data_ ? data_->node_count() : 0; }
const int32_t* TemporalDag::faces() const { return data_ ? data_->faces.data() : nullptr; }
bool TemporalDag::two_sided(size_t face) const { return data_ && !data_->two_sided.empty() && data_->two_sided[face]; }
size_t TemporalDag::input_vertex_count() const { return data_ ? data_->input_points.size() : 0; }
const int32_t* TemporalDag::input_points() const { return data_ ? data_->input_points.data() : nullptr; }
Governing TemporalDag::governing() const { return data_ ? data_->governing : Governing::first; }
AffineBase TemporalDag::affine_base() const { return data_ ? data_->affine_base : AffineBase::first; }

const double* TemporalDag::affine_map(int32_t frame) const { return &data_->maps[static_cast<size_t>(frame) * 12]; }

const float* TemporalDag::residuals(int32_t frame) const {
  return &data_->residuals[static_cast<size_t>(frame) * static_cast<size_t>(data_->vertex_count) * 3];
}

void TemporalDag::frame_positions(int32_t frame, float* out) const {
  apply_affine(affine_map(frame), residuals(frame), static_cast<size_t>(data_->vertex_count), out);
}

int32_t TemporalDag::kept_child(size_t c) const { return data_->kept_child[c]; }
int32_t TemporalDag::removed_child(size_t c) const { return data_->removed_child[c]; }
const TimeTag& TemporalDag::alive(size_t c) const { return data_->alive[c]; }
int32_t TemporalDag::representative(int32_t node) const { return data_->representative[static_cast<size_t>(node)]; }
int32_t TemporalDag::parent_at(int32_t node, int32_t frame) const { return data_->parent_at(node, frame); }

std::vector<int32_t> TemporalDag::dependencies_at(size_t c, int32_t frame) const {
  std::vector<int32_t> out;
  if (!data_->collapse_alive(c, frame)) return out;
  for (int32_t link = data_->dep_offsets[c]; link < data_->dep_offsets[c + 1]; ++link)
    if (data_->link_alive(static_cast<size_t>(link), frame)) out.push_back(data_->dep_nodes[static_cast<size_t>(link)]);
  return out;
}

double TemporalDag::error_bound(size_t c, int32_t frame) const {
  const uint16_t code = data_->error_code(c, frame);
  if (code == detail::kNoCode && !data_->collapse_alive(c, frame)) return std::numeric_limits<double>::infinity();
  return detail::decode_error(code, data_->scale);
}

size_t TemporalDag::dependency_link_count(size_t c) const {
  return static_cast<size_t>(data_->dep_offsets[c + 1] - data_->dep_offsets[c]);
}
size_t TemporalDag::error_run_count(size_t c) const {
  std::vector<uint16_t> codes(static_cast<size_t>(data_->frame_count));
  for (int32_t t = 0; t < data_->frame_count; ++t) codes[static_cast<size_t>(t)] = data_->error_code(c, t);
  size_t runs = 0;
  detail::for_each_error_run(codes.data(), data_->frame_count, [&](int32_t, int32_t, uint16_t) { ++runs; });
  return runs;
}
size_t TemporalDag::error_run_count() const {
  return detail::count_error_runs(data_->codes_by_frame, static_cast<size_t>(data_->frame_count), collapse_count());
}

}  // namespace animlod
