#include "edge_table.hpp"

#include <algorithm>
#include <cstddef>

namespace animlod::detail {

EdgeTable build_edge_table(const int32_t* faces, size_t face_count) {
  // One entry per face side: key = (lower << 32 | higher), then the face, then the direction.
  struct Side {
    uint64_t key;
    int32_t face;
    int32_t reversed;  // 1 when the face goes from the higher to the lower vertex
  };
  // Sorted by (key, face): a counting sort by the lower vertex, then each vertex's few sides
  // sorted alone, instead of one sort of all 3M sides (about 1% of AQEM's instructions on the
  // 24-frame 17k-face sphere, whose motion features build this table).
  uint32_t vertex_count = 0;
  for (size_t i = 0; i < 3 * face_count; ++i) vertex_count = std::max(vertex_count, static_cast<uint32_t>(faces[i]) + 1);
  std::vector<size_t> offsets(static_cast<size_t>(vertex_count) + 1, 0);
  for (size_t f = 0; f < face_count; ++f)
    for (int corner = 0; corner < 3; ++corner) {
      const uint32_t a = static_cast<uint32_t>(faces[3 * f + corner]);
      const uint32_t b = static_cast<uint32_t>(faces[3 * f + (corner + 1) % 3]);
      ++offsets[std::min(a, b) + 1];
    }
  for (size_t v = 0; v < vertex_count; ++v) offsets[v + 1] += offsets[v];
  std::vector<Side> sides(3 * face_count);
  {
    std::vector<size_t> next(offsets.begin(), offsets.end() - 1);
    for (size_t f = 0; f < face_count; ++f)
      for (int corner = 0; corner < 3; ++corner) {
        const uint32_t a = static_cast<uint32_t>(faces[3 * f + corner]);
        const uint32_t b = static_cast<uint32_t>(faces[3 * f + (corner + 1) % 3]);
        const uint64_t key = (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
        sides[next[std::min(a, b)]++] = {key, static_cast<int32_t>(f), a > b ? 1 : 0};
      }
  }
  for (size_t v = 0; v < vertex_count; ++v)
    std::sort(sides.begin() + static_cast<ptrdiff_t>(offsets[v]), sides.begin() + static_cast<ptrdiff_t>(offsets[v + 1]),
              [](const Side& x, const Side& y) { return x.key != y.key ? x.key < y.key : x.face < y.face; });

  EdgeTable table;
  table.vertices.reserve(sides.size() / 2 + 1);
  table.faces.reserve(sides.size() / 2 + 1);
  for (size_t i = 0; i < sides.size();) {
    size_t j = i;
    while (j < sides.size() && sides[j].key == sides[i].key) ++j;
    const std::array<int32_t, 2> edge{static_cast<int32_t>(sides[i].key >> 32),
                                      static_cast<int32_t>(sides[i].key & 0xffffffffu)};
    std::array<int32_t, 2> sided{-1, -1};
    for (size_t k = i; k < j; ++k) {
      int32_t& slot = sided[sides[k].reversed];
      if (slot >= 0 || j - i > 2) {
        if (table.manifold) {
          table.manifold = false;
          table.bad_edge = edge;
          for (size_t n = 0; n < 3 && i + n < j; ++n) table.bad_faces[n] = sides[i + n].face;
        }
        continue;
      }
      slot = sides[k].face;
    }
    table.vertices.push_back(edge);
    table.faces.push_back(sided);
    i = j;
  }
  return table;
}

}  // namespace animlod::detail
