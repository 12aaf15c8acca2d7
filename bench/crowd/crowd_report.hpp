// Frame statistics per mode, and the report: a Markdown table on stdout and a JSON file with one
// object per mode under "modes" (or one row per level under "grid" for Fig. 1), the GL renderer
// string and the run's parameters.
#pragma once

#include <string>
#include <vector>

#include "crowd_animation.hpp"
#include "crowd_options.hpp"
#include "lod_asset.hpp"

namespace crowd {

// Everything measured over the measured frames of one mode (or one grid cell).
struct ModeResult {
  std::string name;
  int mesh_level = -1, motion_level = -1;  // grid cells only
  std::vector<double> frame_ms;       // wall time from swap to swap
  std::vector<double> animation_ms;   // CPU: culling, selection, sampling, FK, palettes
  std::vector<double> upload_ms;      // CPU: gathering palettes and instances into the mapped buffers
  std::vector<double> submit_ms;      // CPU: issuing the draws
  std::vector<double> swap_ms;        // CPU: waiting in the swap (the GPU finishing the frame)
  std::vector<double> gpu_ms;         // timer-query time of the draws (frames whose query returned)
  std::vector<double> round_fps;      // FPS of each round (--rounds)
  double drawn = 0, triangles = 0, joints = 0, palette_joints = 0, updates = 0, draw_calls = 0;  // sums
  std::vector<double> levels = std::vector<double>(16, 0.0);  // sums per level index

  void add(const FrameCounts& counts, size_t buckets, size_t palette_joints_uploaded);
};

struct RunInfo {
  std::string renderer, gl_version;
  bool persistent_mapping = false, timer_queries = false;
  int width = 0, height = 0;
  const CrowdOptions* options = nullptr;
  const std::vector<Asset>* assets = nullptr;
  double load_seconds = 0.0;
};

std::string markdown_report(const RunInfo& info, const std::vector<ModeResult>& results);
std::string json_report(const RunInfo& info, const std::vector<ModeResult>& results);

// Writes `text` to `path` through a temporary file renamed at the end. False on failure.
bool write_atomically(const std::string& path, const std::string& text);

}  // namespace crowd
