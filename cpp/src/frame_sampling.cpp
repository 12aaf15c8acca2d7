#include "frame_sampling.hpp"

#include <algorithm>
#include <limits>

#include "worker_threads.hpp"

namespace animlod::detail {

namespace {
double squared_distance(const AnimatedMeshView& mesh, size_t a, size_t b) {
  const size_t values = mesh.vertex_count * 3;
  const float* pa = mesh.frames + a * values;
  const float* pb = mesh.frames + b * values;
  double sum = 0.0;
  for (size_t i = 0; i < values; ++i) {
    const double d = static_cast<double>(pa[i]) - pb[i];
    sum += d * d;
  }
  return sum;
}
}  // namespace

std::vector<int32_t> sample_frames(const AnimatedMeshView& mesh, size_t count) {
  count = std::min(count, mesh.frame_count);
  std::vector<int32_t> chosen;
  if (count == 0) return chosen;
  std::vector<double> nearest(mesh.frame_count, std::numeric_limits<double>::infinity());
  std::vector<uint8_t> taken(mesh.frame_count, 0);
  // A long dense capture's distances are most of the cost: the frames not taken are measured on
  // every core (each distance is its own, so the choice does not depend on the threads).
  const size_t workers =
      mesh.frame_count * mesh.vertex_count >= (size_t{1} << 20) ? std::min<size_t>(thread_limit(), mesh.frame_count) : 1;
  size_t next = 0;
  while (chosen.size() < count) {
    chosen.push_back(static_cast<int32_t>(next));
    taken[next] = 1;
    nearest[next] = 0.0;
    run_in_ranges(mesh.frame_count, workers, [&](size_t begin, size_t end, size_t) {
      for (size_t f = begin; f < end; ++f)
        if (!taken[f]) nearest[f] = std::min(nearest[f], squared_distance(mesh, f, next));
    });
    // Identical poses tie at distance 0; the earliest frame not taken yet wins.
    size_t farthest = mesh.frame_count;
    for (size_t f = 0; f < mesh.frame_count; ++f)
      if (!taken[f] && (farthest == mesh.frame_count || nearest[f] > nearest[farthest])) farthest = f;
    next = farthest;
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

}  // namespace animlod::detail
