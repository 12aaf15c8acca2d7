// Times animlod::simplify_animated (the C++ core alone, no Python) on a mesh file written by
// run.sh: int64 F, V, M, then (F, V, 3) float32 frames and (M, 3) int32 faces. Simplifies to 10%
// of the faces, motion features off unless the third argument is 1, and prints the best of N
// runs with a hash of the level (faces and positions) and the summed collapse cost, so that
// steps that keep the collapse order show it.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "animlod/aqem.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: aqem_time MESH.bin [REPEATS] [FEATURES]\n");
    return 2;
  }
  FILE* file = std::fopen(argv[1], "rb");
  int64_t header[3];
  if (!file || std::fread(header, 8, 3, file) != 3) return 2;
  std::vector<float> frames(static_cast<size_t>(header[0] * header[1] * 3));
  std::vector<int32_t> faces(static_cast<size_t>(header[2] * 3));
  if (std::fread(frames.data(), 4, frames.size(), file) != frames.size()) return 2;
  if (std::fread(faces.data(), 4, faces.size(), file) != faces.size()) return 2;
  std::fclose(file);
  const animlod::AnimatedMeshView view{frames.data(), faces.data(), static_cast<size_t>(header[0]),
                                       static_cast<size_t>(header[1]), static_cast<size_t>(header[2])};
  animlod::AqemOptions options;
  options.use_motion_features = argc > 3 && std::atoi(argv[3]) != 0;
  options.target_ratios = {0.1};
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 1;
  double best = 1e300;
  animlod::AqemResult result;
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    const animlod::Status status = animlod::simplify_animated(view, animlod::AqemVertexData{}, options, result);
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (!status) {
      std::fprintf(stderr, "%s\n", status.message.c_str());
      return 1;
    }
  }
  const animlod::AqemLevel& level = result.levels[0];
  double cost = 0.0;
  for (double c : result.collapses.cost) cost += c;
  uint64_t hash = 1469598103934665603ull;  // FNV-1a over the faces and the position bits
  auto mix = [&hash](uint32_t value) {
    hash ^= value;
    hash *= 1099511628211ull;
  };
  for (int32_t v : level.faces) mix(static_cast<uint32_t>(v));
  for (float v : level.positions) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    mix(bits);
  }
  std::printf("%.3f|%zu|%.6g|%.8g|%016llx\n", best, level.faces.size() / 3, level.error, cost,
              static_cast<unsigned long long>(hash));
  return 0;
}
