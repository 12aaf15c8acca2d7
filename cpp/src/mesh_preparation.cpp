#include "mesh_preparation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <utility>

#include "union_find.hpp"
#include "worker_threads.hpp"

namespace animlod::detail {

namespace {

// Lexicographic order of two float rows; equal rows compare equal whatever their bits (-0 == 0).
int compare_rows(const float* a, const float* b, size_t count, size_t stride_a, size_t stride_b) {
  for (size_t i = 0; i < count; ++i) {
    const float x = a[i * stride_a], y = b[i * stride_b];
    if (x < y) return -1;
    if (y < x) return 1;
  }
  return 0;
}

// Values closer than this fraction of the mesh's extent (positions and the values that move with
// them), or than this weight, are one value to the weld: two copies of a seam that different
// computations wrote (sin(2 pi) for sin(0), a delta one ulp off) are no seam. About 8 float ulps
// at the extent; an absolute floor keeps a mesh of one point finite.
constexpr double kWeldTolerance = 1e-6;

// A value snapped to the weld's grid: values within one cell compare equal, -0 and 0 too.
// Snapping keeps every exactly equal pair equal; a near pair that straddles a cell boundary stays
// apart, as before the tolerance.
int64_t snapped(float value, double inverse_cell) {
  const double scaled = static_cast<double>(value) * inverse_cell;
  if (std::fabs(scaled) < 4e18) return static_cast<int64_t>(scaled + std::copysign(0.5, scaled));  // llround, inlined
  // Far from the origin against the extent: the value itself, below every snapped one.
  uint32_t bits;
  value += 0.0f;  // -0 + 0 is +0
  std::memcpy(&bits, &value, sizeof bits);
  return std::numeric_limits<int64_t>::min() + static_cast<int64_t>(bits);
}

// Influence k of vertex v's weight on the weld's grid.
int64_t snapped_weight(const WeldInput& input, size_t v, size_t k) {
  return snapped(input.skin_weights[v * input.influence_count + k], 1.0 / kWeldTolerance);
}

// Skin rows compare as snapped (joint, weight) sets: influences whose weight snaps to zero do
// not count, and the order of the influences does not matter.
std::vector<std::pair<int32_t, int64_t>> skin_set(const WeldInput& input, size_t v) {
  std::vector<std::pair<int32_t, int64_t>> set;
  for (size_t k = 0; k < input.influence_count; ++k) {
    const int64_t weight = snapped_weight(input, v, k);
    if (weight > 0) set.emplace_back(input.skin_joints[v * input.influence_count + k], weight);
  }
  std::sort(set.begin(), set.end());
  return set;
}

// 1 / the weld's cell: in each frame, kWeldTolerance of that frame's extent of the used vertices
// or of the median frame's if larger (a frame where the mesh shrinks keeps the cell that welds
// its seams); for the position attributes, of the median frame's. Per frame: with one cell for
// every frame, a stray vertex far out in one frame made the cell as coarse in all of them, and
// real vertices welded (a vertex at 1e6 on a 1.7-unit body left 238 of 13,776 faces).
struct WeldCells {
  std::vector<double> inverse_frame;  // (F,)
  double inverse_attribute = 0.0;
};

WeldCells weld_cells(const AnimatedMeshView& mesh, const std::vector<uint8_t>& used) {
  std::vector<double> extents(mesh.frame_count, 0.0);
  for (size_t frame = 0; frame < mesh.frame_count; ++frame) {
    std::array<float, 3> low{}, high{};
    bool first = true;
    for (size_t v = 0; v < mesh.vertex_count; ++v) {
      if (!used[v]) continue;
      const float* p = mesh.frames + (frame * mesh.vertex_count + v) * 3;
      for (size_t axis = 0; axis < 3; ++axis) {
        low[axis] = first ? p[axis] : std::min(low[axis], p[axis]);
        high[axis] = first ? p[axis] : std::max(high[axis], p[axis]);
      }
      first = false;
    }
    for (size_t axis = 0; axis < 3; ++axis)
      extents[frame] = std::max(extents[frame], static_cast<double>(high[axis]) - static_cast<double>(low[axis]));
  }
  std::vector<double> sorted = extents;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  const double median = std::max(sorted.empty() ? 0.0 : *middle, 1e-30);
  WeldCells cells;
  for (const double extent : extents) cells.inverse_frame.push_back(1.0 / (kWeldTolerance * std::max(extent, median)));
  cells.inverse_attribute = 1.0 / (kWeldTolerance * median);
  return cells;
}

// Step 1: vertices equal in every frame, in position attributes and in skin (each snapped to the
// weld's grid) share a point. Returns (V,) the lowest input vertex each referenced vertex welds
// with (itself if none), -1 for unreferenced vertices. As meshoptimizer's position remap: an
// open-addressing table keyed by a hash of everything compared holds the first vertex of each
// class met in input order, the lowest.
std::vector<int32_t> weld(const AnimatedMeshView& mesh, const WeldInput& input, const std::vector<uint8_t>& used) {
  const size_t vertex_count = mesh.vertex_count;
  const size_t frame_stride = vertex_count * 3;
  std::vector<int32_t> welded_to(vertex_count, -1);
  if (!input.weld) {
    for (size_t v = 0; v < vertex_count; ++v)
      if (used[v]) welded_to[v] = static_cast<int32_t>(v);
    return welded_to;
  }
  const WeldCells cells = weld_cells(mesh, used);
  auto same_rows = [&](const float* a, const float* b, size_t count, double inverse_cell) {
    for (size_t i = 0; i < count; ++i)
      if (snapped(a[i], inverse_cell) != snapped(b[i], inverse_cell)) return false;
    return true;
  };
  auto equal = [&](int32_t a, int32_t b) {
    for (size_t frame = 0; frame < mesh.frame_count; ++frame) {
      const float* pa = mesh.frames + frame * frame_stride + static_cast<size_t>(a) * 3;
      const float* pb = mesh.frames + frame * frame_stride + static_cast<size_t>(b) * 3;
      if (!same_rows(pa, pb, 3, cells.inverse_frame[frame])) return false;
    }
    const size_t width = input.position_attribute_count;
    if (width && !same_rows(input.position_attributes + static_cast<size_t>(a) * width,
                            input.position_attributes + static_cast<size_t>(b) * width, width,
                            cells.inverse_attribute))
      return false;
    return !input.skin_joints || skin_set(input, static_cast<size_t>(a)) == skin_set(input, static_cast<size_t>(b));
  };
  // Over everything `equal` compares, so that only equal vertices share a probe sequence (a
  // mesh whose vertices all start at one spot must not chain them all).
  auto mix = [](uint64_t h, int64_t value) {
    h = (h ^ static_cast<uint64_t>(value)) * 0xff51afd7ed558ccdull;
    return h ^ (h >> 32);
  };
  auto hash = [&](size_t v) {
    uint64_t h = 0x9e3779b97f4a7c15ull;
    for (size_t frame = 0; frame < mesh.frame_count; ++frame)
      for (size_t axis = 0; axis < 3; ++axis)
        h = mix(h, snapped(mesh.frames[frame * frame_stride + v * 3 + axis], cells.inverse_frame[frame]));
    for (size_t b = 0; b < input.position_attribute_count; ++b)
      h = mix(h, snapped(input.position_attributes[v * input.position_attribute_count + b], cells.inverse_attribute));
    uint64_t skin = 0;  // a sum: the influences' order does not count, zero weights do not count
    for (size_t k = 0; input.skin_joints && k < input.influence_count; ++k) {
      const int64_t weight = snapped_weight(input, v, k);
      if (weight > 0) skin += mix(static_cast<uint64_t>(input.skin_joints[v * input.influence_count + k]), weight);
    }
    return h ^ skin;
  };
  size_t capacity = 16;
  while (capacity < 2 * vertex_count) capacity *= 2;
  std::vector<int32_t> table(capacity, -1);
  for (size_t v = 0; v < vertex_count; ++v) {
    if (!used[v]) continue;
    for (size_t slot = hash(v) & (capacity - 1);; slot = (slot + 1) & (capacity - 1)) {
      if (table[slot] < 0) {
        table[slot] = static_cast<int32_t>(v);
        welded_to[v] = static_cast<int32_t>(v);
        break;
      }
      if (equal(table[slot], static_cast<int32_t>(v))) {
        welded_to[v] = table[slot];
        break;
      }
    }
  }
  return welded_to;
}

// Whether the faces of two opposite sides (a -> b starting at corner `forward`, b -> a at
// `backward`) are one triangle turned over: their third points agree.
bool same_triangle(const std::vector<int32_t>& corner_points, int32_t forward, int32_t backward) {
  return corner_points[static_cast<size_t>(next_corner(next_corner(forward)))] ==
         corner_points[static_cast<size_t>(next_corner(next_corner(backward)))];
}

// Corners of one point are joined when their faces are paired across an edge at that point.
struct Side {
  uint64_t key;    // (lower point << 32) | higher point
  int32_t corner;  // corner of the side's start point; (corner / 3) is the face
  int32_t forward; // 1 when the side runs from the lower to the higher point
};

uint64_t edge_key(int32_t a, int32_t b) {
  const auto low = static_cast<uint32_t>(std::min(a, b)), high = static_cast<uint32_t>(std::max(a, b));
  return (static_cast<uint64_t>(low) << 32) | high;
}

// Items bucketed by a point in [0, point_count) with a counting sort: bucket p holds
// [offsets[p], offsets[p + 1]) of the order, items in increasing index within a bucket. O(n),
// and the buckets are small (a point's edges), so sorting inside them is cheap.
template <typename PointOf>
void bucket_by_point(size_t item_count, size_t point_count, PointOf point_of, std::vector<int32_t>& offsets,
                     std::vector<int32_t>& order) {
  offsets.assign(point_count + 1, 0);
  for (size_t i = 0; i < item_count; ++i) ++offsets[static_cast<size_t>(point_of(i)) + 1];
  for (size_t p = 0; p < point_count; ++p) offsets[p + 1] += offsets[p];
  order.resize(item_count);
  std::vector<int32_t> cursor(offsets.begin(), offsets.end() - 1);
  for (size_t i = 0; i < item_count; ++i) order[static_cast<size_t>(cursor[static_cast<size_t>(point_of(i))]++)] =
      static_cast<int32_t>(i);
}

constexpr size_t kCornersPerWorker = 1 << 17;  // fewer corners per worker: one worker

size_t workers_for(size_t corner_count) {
  return halves_from(corner_count, 2 * kCornersPerWorker);
}

// The simple case of pair_sides without sorting every side: each side a -> b looks for its
// directed edge among the sides leaving a (it must be the only one) and for b -> a among those
// leaving b (at most one, not its own triangle turned over). A point's sides are few and
// scanned; a point with more than kScannedSides (a sphere's pole, a disc fanned from its
// centre) has its sides sorted by end point and searched, since scanning would grow with the
// square of its sides. Fills `partner` as pair_sides would and returns true when the mesh is
// simple; returns false as soon as it is not. A repeated face repeats its directed edges, so a
// simple mesh has none.
bool pair_unique_sides(const std::vector<int32_t>& corner_points, size_t point_count, std::vector<int32_t>& partner) {
  constexpr int32_t kScannedSides = 32;
  const size_t corner_count = corner_points.size();
  std::vector<int32_t> offsets, order;
  bucket_by_point(corner_count, point_count, [&](size_t c) { return corner_points[c]; }, offsets, order);
  std::vector<std::pair<int32_t, int32_t>> leaving(corner_count);  // (end point, corner) by start point
  for (size_t i = 0; i < corner_count; ++i) {
    const auto c = static_cast<size_t>(order[i]);
    leaving[i] = {corner_points[next_corner(c)], order[i]};
  }
  for (size_t p = 0; p < point_count; ++p)
    if (offsets[p + 1] - offsets[p] > kScannedSides)
      std::sort(leaving.begin() + offsets[p], leaving.begin() + offsets[p + 1]);
  // How many sides run from a to b; `corner` is set to one of them.
  auto sides_between = [&](int32_t a, int32_t b, int32_t& corner) {
    const auto first = leaving.begin() + offsets[a], last = leaving.begin() + offsets[a + 1];
    if (last - first > kScannedSides) {
      const auto [from, to] = std::equal_range(first, last, std::pair<int32_t, int32_t>{b, 0},
                                               [](const auto& x, const auto& y) { return x.first < y.first; });
      if (from != to) corner = from->second;
      return static_cast<int>(to - from);
    }
    int count = 0;
    for (auto side = first; side != last; ++side)
      if (side->first == b) ++count, corner = side->second;
    return count;
  };
  partner.assign(corner_count, -1);
  const size_t workers = workers_for(corner_count);
  std::vector<uint8_t> simple(workers, 1);
  run_in_ranges(corner_count, workers, [&](size_t begin, size_t end, size_t worker) {
    for (size_t c = begin; c < end; ++c) {
      const int32_t a = corner_points[c], b = corner_points[next_corner(c)];
      int32_t same = -1, opposite = -1;
      const int same_way = sides_between(a, b, same), other_way = sides_between(b, a, opposite);
      if (same_way > 1 || other_way > 1 ||
          (opposite >= 0 && same_triangle(corner_points, static_cast<int32_t>(c), opposite))) {
        simple[worker] = 0;
        return;
      }
      partner[c] = opposite;
    }
  });
  return std::all_of(simple.begin(), simple.end(), [](uint8_t flag) { return flag != 0; });
}

// Step 3's pairing: across every undirected edge, sides are paired first-come in face order,
// one forward with one backward; unpaired sides are borders of their piece. Sides are visited
// in (edge, corner) order: bucketed by their lower point, then sorted by (higher point, corner)
// inside the bucket. Large meshes take two workers, one for each half of the buckets (an edge's
// sides lie in one). Fills `partner`, the corner of the side paired with each side (a side
// starts at its corner), -1 for a border. Returns whether the mesh is simple: every undirected
// edge has at most one side each way and both are paired (then no directed edge repeats,
// whatever the fans, and the pairing is the one OpenMesh's add_face would make).
bool pair_sides(const std::vector<int32_t>& corner_points, size_t point_count, std::vector<int32_t>& partner) {
  const size_t corner_count = corner_points.size();
  const size_t workers = workers_for(corner_count);
  auto end_point = [&](size_t c) { return corner_points[next_corner(c)]; };
  std::vector<int32_t> offsets, order;
  bucket_by_point(corner_count, point_count, [&](size_t c) { return std::min(corner_points[c], end_point(c)); },
                  offsets, order);
  partner.assign(corner_count, -1);
  std::vector<Side> sorted(corner_count);
  std::vector<uint8_t> simple(workers, 1);
  run_in_ranges(point_count, workers, [&](size_t first_point, size_t last_point, size_t worker) {
    const auto begin = static_cast<size_t>(offsets[first_point]), end = static_cast<size_t>(offsets[last_point]);
    for (size_t i = begin; i < end; ++i) {
      const auto c = static_cast<size_t>(order[i]);
      const int32_t a = corner_points[c], b = end_point(c);
      sorted[i] = {edge_key(a, b), static_cast<int32_t>(c), a < b ? 1 : 0};
    }
    for (size_t p = first_point; p < last_point; ++p)
      std::sort(sorted.begin() + offsets[p], sorted.begin() + offsets[p + 1],
                [](const Side& x, const Side& y) { return x.key != y.key ? x.key < y.key : x.corner < y.corner; });
    std::vector<int32_t> forward, backward;
    std::vector<uint8_t> taken;
    for (size_t i = begin; i < end;) {
      size_t j = i;
      while (j < end && sorted[j].key == sorted[i].key) ++j;
      forward.clear();
      backward.clear();
      for (size_t k = i; k < j; ++k) (sorted[k].forward ? forward : backward).push_back(sorted[k].corner);
      simple[worker] &= forward.size() <= 1 && backward.size() <= 1;
      taken.assign(backward.size(), 0);
      for (const int32_t ca : forward) {
        // The first free opposite side, unless its face is the same triangle turned over (a
        // two-sided sheet): joining those would fold the surface onto itself.
        size_t match = 0;
        while (match < backward.size() && (taken[match] || same_triangle(corner_points, ca, backward[match])))
          ++match;
        if (match == backward.size()) {
          simple[worker] &= backward.empty();
          continue;
        }
        taken[match] = 1;
        partner[static_cast<size_t>(ca)] = backward[match];
        partner[static_cast<size_t>(backward[match])] = ca;
      }
      i = j;
    }
  });
  return std::all_of(simple.begin(), simple.end(), [](uint8_t flag) { return flag != 0; });
}

// Paired sides join the corners of their points into fans, each labelled by its lowest corner.
// Side a -> b starts at corner ca (point a) and ends at the next corner (point b); its partner
// b -> a starts at cb (point b): ca joins next(cb) at a, and cb joins next(ca) at b. Large meshes
// take two workers, one for each half of the points (a pairing joins corners of one point only,
// and the labels do not depend on the order of the joins).
std::vector<int32_t> join_fans(const std::vector<int32_t>& corner_points, size_t point_count,
                               const std::vector<int32_t>& partner) {
  const size_t corner_count = corner_points.size();
  const size_t workers = workers_for(corner_count);
  UnionFind fans(corner_count);
  std::vector<int32_t> label(corner_count);
  const auto half_point = static_cast<int32_t>(point_count / 2);
  run_in_ranges(workers, workers, [&](size_t, size_t, size_t worker) {
    auto mine = [&](size_t c) { return workers == 1 || (corner_points[c] >= half_point) == (worker == 1); };
    for (size_t c = 0; c < corner_count; ++c)
      if (mine(c) && partner[c] >= 0) fans.unite(static_cast<int32_t>(c), next_corner(partner[c]));
    for (size_t c = 0; c < corner_count; ++c)
      if (mine(c)) label[c] = fans.find(static_cast<int32_t>(c));
  });
  return label;
}

// Step 2's repeats: faces with the points of a face before them in the same turn (sorted by
// (rotated corners, face) inside buckets of their lowest point) leave the corner and face
// lists; with `mirror_sources` and `mirror_vertices` (not null), so do faces with the points of
// a face before them in the reverse turn, each recorded in the first (aligned with the faces
// that stay) as its earlier face's mirror, and its corners' input vertices in the second, each
// with the earlier face's at the same point. Returns how many left as repeats.
size_t drop_repeated_faces(std::vector<int32_t>& corner_points, std::vector<int32_t>& corner_inputs,
                           std::vector<int32_t>& face_sources, size_t point_count,
                           std::vector<int32_t>* mirror_sources, std::vector<int32_t>* mirror_vertices) {
  using Rotated = std::pair<std::array<int32_t, 3>, int32_t>;  // canonical rotation, face
  const size_t face_count = face_sources.size();
  std::vector<Rotated> rotated(face_count);
  for (size_t f = 0; f < face_count; ++f) {
    const int32_t* p = &corner_points[3 * f];
    const auto first = static_cast<size_t>(std::min_element(p, p + 3) - p);
    rotated[f] = {{p[first], p[(first + 1) % 3], p[(first + 2) % 3]}, static_cast<int32_t>(f)};
  }
  std::vector<int32_t> offsets, order;
  bucket_by_point(face_count, point_count, [&](size_t f) { return rotated[f].first[0]; }, offsets, order);
  std::vector<Rotated> sorted(face_count);
  for (size_t i = 0; i < face_count; ++i) sorted[i] = rotated[static_cast<size_t>(order[i])];
  for (size_t p = 0; p < point_count; ++p) std::sort(sorted.begin() + offsets[p], sorted.begin() + offsets[p + 1]);
  std::vector<uint8_t> repeated(face_count, 0);
  for (size_t i = 1; i < face_count; ++i)
    if (sorted[i].first == sorted[i - 1].first) repeated[static_cast<size_t>(sorted[i].second)] = 1;
  // The first face of a rotation is no repeat; the first of the reversed rotation, if earlier,
  // is the one a face mirrors (it mirrors no face itself: its own mirror would be earlier still
  // and have this face's rotation, making this face a repeat).
  std::vector<int32_t> mirror_of(mirror_sources ? face_count : 0, -1);
  for (size_t f = 0; f < mirror_of.size(); ++f) {
    if (repeated[f]) continue;
    const std::array<int32_t, 3>& r = rotated[f].first;
    const Rotated reversed{{r[0], r[2], r[1]}, -1};
    const auto first = sorted.begin() + offsets[static_cast<size_t>(r[0])];
    const auto last = sorted.begin() + offsets[static_cast<size_t>(r[0]) + 1];
    const auto found = std::lower_bound(first, last, reversed);
    if (found != last && found->first == reversed.first && static_cast<size_t>(found->second) < f)
      mirror_of[f] = found->second;
  }
  // The input face of each face's mirror, by face (before the lists close up).
  std::vector<int32_t> mirror_input(mirror_of.size(), -1);
  bool any_mirror = false;
  for (size_t f = 0; f < mirror_of.size(); ++f) {
    if (mirror_of[f] < 0) continue;
    const auto front = static_cast<size_t>(mirror_of[f]);
    mirror_input[front] = face_sources[f];
    any_mirror = true;
    for (size_t k = 0; k < 3; ++k)
      for (size_t j = 0; j < 3; ++j)
        if (corner_points[3 * f + k] == corner_points[3 * front + j])
          mirror_vertices->insert(mirror_vertices->end(), {corner_inputs[3 * f + k], corner_inputs[3 * front + j]});
  }
  if (any_mirror) mirror_sources->clear();
  size_t kept = 0;
  for (size_t f = 0; f < face_count; ++f) {
    if (repeated[f] || (!mirror_of.empty() && mirror_of[f] >= 0)) continue;
    if (any_mirror) mirror_sources->push_back(mirror_input[f]);
    face_sources[kept] = face_sources[f];
    for (size_t k = 0; k < 3; ++k) {
      corner_points[3 * kept + k] = corner_points[3 * f + k];
      corner_inputs[3 * kept + k] = corner_inputs[3 * f + k];
    }
    ++kept;
  }
  const auto repeats = static_cast<size_t>(std::count(repeated.begin(), repeated.end(), 1));
  face_sources.resize(kept);
  corner_points.resize(3 * kept);
  corner_inputs.resize(3 * kept);
  return repeats;
}

// Faces that repeat a directed edge of a face before them (the lowest face keeps it): bucketed
// by the edge's start point, sorted by (end point, face) inside the bucket. Returns whether any.
bool repeated_directed_edges(const std::vector<int32_t>& corner_points, size_t point_count,
                             std::vector<uint8_t>& loose) {
  const size_t corner_count = corner_points.size();
  std::vector<int32_t> offsets, order;
  bucket_by_point(corner_count, point_count, [&](size_t c) { return corner_points[c]; }, offsets, order);
  loose.assign(corner_count / 3, 0);
  bool any = false;
  std::vector<std::pair<int32_t, int32_t>> outgoing;  // (end point, face)
  for (size_t p = 0; p < point_count; ++p) {
    outgoing.clear();
    for (int32_t k = offsets[p]; k < offsets[p + 1]; ++k) {
      const int32_t c = order[static_cast<size_t>(k)];
      outgoing.emplace_back(corner_points[static_cast<size_t>(next_corner(c))], c / 3);
    }
    std::sort(outgoing.begin(), outgoing.end());
    for (size_t i = 1; i < outgoing.size(); ++i)
      if (outgoing[i].first == outgoing[i - 1].first) loose[static_cast<size_t>(outgoing[i].second)] = any = true;
  }
  return any;
}

}  // namespace

PreparedMesh prepare_mesh(const AnimatedMeshView& mesh, const WeldInput& input) {
  PreparedMesh out;
  const size_t vertex_count = mesh.vertex_count;
  std::vector<uint8_t> used(vertex_count, 0);
  for (size_t i = 0; i < 3 * mesh.face_count; ++i) used[mesh.faces[i]] = 1;
  out.unreferenced_vertices = static_cast<size_t>(std::count(used.begin(), used.end(), 0));
  const std::vector<int32_t> welded_to = weld(mesh, input, used);

  // Points numbered in input order of their lowest vertex, so that a mesh with nothing to
  // weld keeps its vertex numbering.
  std::vector<int32_t> point_of(vertex_count, -1);
  for (size_t v = 0; v < vertex_count; ++v) {
    if (welded_to[v] < 0) continue;
    if (welded_to[v] == static_cast<int32_t>(v)) {
      point_of[v] = static_cast<int32_t>(out.point_source.size());
      out.point_source.push_back(static_cast<int32_t>(v));
    } else {
      point_of[v] = point_of[welded_to[v]];
      ++out.welded_vertices;
    }
  }

  // Step 2: faces in point terms; drop degenerate ones and repeats (same points, same turn;
  // with mirror_two_sided also the reverse turn, recorded as mirrors).
  // Written in place (a range insert per face took most of this step's time at 1M faces).
  std::vector<int32_t> corner_points(3 * mesh.face_count), corner_inputs(3 * mesh.face_count);
  out.face_sources.reserve(mesh.face_count);
  size_t kept = 0;
  for (size_t f = 0; f < mesh.face_count; ++f) {
    const int32_t* v = mesh.faces + 3 * f;
    const std::array<int32_t, 3> p{point_of[v[0]], point_of[v[1]], point_of[v[2]]};
    if (p[0] == p[1] || p[1] == p[2] || p[0] == p[2]) {
      ++out.degenerate_faces;
      continue;
    }
    out.face_sources.push_back(static_cast<int32_t>(f));
    for (int k = 0; k < 3; ++k) {
      corner_inputs[3 * kept + k] = v[k];
      corner_points[3 * kept + k] = p[k];
    }
    ++kept;
  }
  corner_inputs.resize(3 * kept);
  corner_points.resize(3 * kept);
  // A mesh with every directed edge once (the common case) repeats no face, and its sides pair
  // without sorting (step 3).
  std::vector<int32_t> partner;
  bool simple = pair_unique_sides(corner_points, out.point_source.size(), partner);
  if (!simple) {
    const size_t before = out.face_sources.size();
    out.duplicate_faces = drop_repeated_faces(corner_points, corner_inputs, out.face_sources, out.point_source.size(),
                                              input.mirror_two_sided ? &out.mirror_sources : nullptr,
                                              input.mirror_two_sided ? &out.mirror_vertices : nullptr);
    out.mirrored_faces = before - out.duplicate_faces - out.face_sources.size();
    simple = pair_sides(corner_points, out.point_source.size(), partner);
  }

  // Step 3: split points into fans until no directed edge is used twice. A fan that winds
  // around its point more than once still repeats a directed edge: such a face is cut loose
  // (three new points), which ends the loop since its points are its own.
  out.point_split.assign(out.point_source.size(), 0);
  while (true) {
    const std::vector<int32_t> label = join_fans(corner_points, out.point_source.size(), partner);
    // One point per (point, fan); the fan of the lowest corner keeps the point's index.
    std::vector<int32_t> fan_point(corner_points.size(), -1);
    std::vector<int32_t> first_fan(out.point_source.size(), -1);
    for (size_t c = 0; c < corner_points.size(); ++c) {
      const int32_t p = corner_points[c], fan = label[c];
      if (fan_point[fan] >= 0) continue;
      if (first_fan[p] < 0) {
        first_fan[p] = fan;
        fan_point[fan] = p;
      } else {
        fan_point[fan] = static_cast<int32_t>(out.point_source.size());
        out.point_source.push_back(out.point_source[p]);
        out.point_split.push_back(1);
        out.point_split[p] = 1;
        ++out.split_points;
      }
    }
    for (size_t c = 0; c < corner_points.size(); ++c) corner_points[c] = fan_point[label[c]];
    if (simple) {
      out.side_partners = std::move(partner);
      break;
    }

    std::vector<uint8_t> loose;
    const bool any = repeated_directed_edges(corner_points, out.point_source.size(), loose);
    if (!any) break;
    for (size_t f = 0; f < loose.size(); ++f) {
      if (!loose[f]) continue;
      for (int k = 0; k < 3; ++k) {
        int32_t& p = corner_points[3 * f + k];
        const int32_t old_point = p;
        out.point_split[old_point] = 1;
        p = static_cast<int32_t>(out.point_source.size());
        out.point_source.push_back(out.point_source[old_point]);
        out.point_split.push_back(1);
        ++out.split_points;
      }
    }
    simple = pair_sides(corner_points, out.point_source.size(), partner);
  }
  // A point whose only faces were cut loose is left without corners: renumber the points.
  std::vector<int32_t> renumber(out.point_source.size(), -1);
  for (int32_t p : corner_points) renumber[p] = 0;
  if (std::find(renumber.begin(), renumber.end(), -1) != renumber.end()) {
    std::vector<int32_t> sources;
    std::vector<uint8_t> split;
    for (size_t p = 0; p < renumber.size(); ++p) {
      if (renumber[p] < 0) continue;
      renumber[p] = static_cast<int32_t>(sources.size());
      sources.push_back(out.point_source[p]);
      split.push_back(out.point_split[p]);
    }
    out.point_source = std::move(sources);
    out.point_split = std::move(split);
    for (int32_t& p : corner_points) p = renumber[p];
  }
  out.faces = std::move(corner_points);

  // Step 4: wedges of one point with equal attributes and face group merge into the lowest.
  out.wedge_point.assign(vertex_count, -1);
  for (size_t c = 0; c < corner_inputs.size(); ++c) out.wedge_point[corner_inputs[c]] = out.faces[c];
  std::vector<int32_t> wedge_group(vertex_count, 0);
  if (input.face_groups)
    for (size_t c = corner_inputs.size(); c-- > 0;)  // the first face using a vertex decides its group
      wedge_group[corner_inputs[c]] = input.face_groups[out.face_sources[c / 3]];
  std::vector<int32_t> used_vertices;
  for (size_t v = 0; v < vertex_count; ++v)
    if (out.wedge_point[v] >= 0) used_vertices.push_back(static_cast<int32_t>(v));
  const size_t width = input.attribute_count;
  auto wedge_less = [&](int32_t a, int32_t b) {
    if (out.wedge_point[a] != out.wedge_point[b]) return out.wedge_point[a] < out.wedge_point[b];
    if (wedge_group[a] != wedge_group[b]) return wedge_group[a] < wedge_group[b];
    if (!width) return false;
    return compare_rows(input.attributes + static_cast<size_t>(a) * width,
                        input.attributes + static_cast<size_t>(b) * width, width, 1, 1) < 0;
  };
  // Stably sorted by wedge_less: bucketed by point in vertex order, each bucket then sorted.
  std::vector<int32_t> offsets, order;
  bucket_by_point(used_vertices.size(), out.point_source.size(),
                  [&](size_t i) { return out.wedge_point[used_vertices[i]]; }, offsets, order);
  std::vector<int32_t> wedges(used_vertices.size());
  for (size_t i = 0; i < wedges.size(); ++i) wedges[i] = used_vertices[static_cast<size_t>(order[i])];
  for (size_t p = 0; p < out.point_source.size(); ++p)
    if (offsets[p + 1] - offsets[p] > 1)
      std::stable_sort(wedges.begin() + offsets[p], wedges.begin() + offsets[p + 1], wedge_less);
  out.wedge_representative.assign(vertex_count, -1);
  std::vector<int32_t> wedges_at_point(out.point_source.size(), 0);
  for (size_t i = 0; i < wedges.size();) {
    size_t j = i + 1;
    while (j < wedges.size() && !wedge_less(wedges[i], wedges[j])) ++j;
    for (size_t k = i; k < j; ++k) out.wedge_representative[wedges[k]] = wedges[i];
    ++wedges_at_point[out.wedge_point[wedges[i]]];
    i = j;
  }
  out.seam_points = static_cast<size_t>(std::count_if(wedges_at_point.begin(), wedges_at_point.end(),
                                                      [](int32_t count) { return count > 1; }));
  // Where three or more attribute charts meet, no collapse keeps every chart's corner: the
  // point stays where it is (meshoptimizer's "complex" vertices), like a cut point.
  for (size_t p = 0; p < wedges_at_point.size(); ++p)
    if (wedges_at_point[p] > 2) out.point_split[p] = 1;
  out.corner_wedges.resize(corner_inputs.size());
  for (size_t c = 0; c < corner_inputs.size(); ++c) out.corner_wedges[c] = out.wedge_representative[corner_inputs[c]];
  return out;
}

}  // namespace animlod::detail
