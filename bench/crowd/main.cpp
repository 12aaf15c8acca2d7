// animlod_crowd: the native crowd benchmark of animlod (issue 9; the motion LoD paper's Table 2
// and Fig. 1, seeds/000 Sections 1 and 6.4). Reads LoD GLBs, places N characters, flies the
// camera along a path and measures frame times for each LoD mode side by side in one run.
//
// Exit codes: 0 done, 1 an output could not be written, 2 bad input (arguments, files),
// 3 no usable OpenGL context (no display, GL older than 3.3 core).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <new>
#include <string>
#include <vector>

#include "crowd_animation.hpp"
#include "crowd_options.hpp"
#include "crowd_report.hpp"
#include "crowd_scene.hpp"
#include "gl_renderer.hpp"
#include "lod_asset.hpp"

namespace {

using Clock = std::chrono::steady_clock;

double milliseconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

int fail(int code, const std::string& message) {
  std::fprintf(stderr, "animlod_crowd: error: %s\n", message.c_str());
  return code;
}

// The (mesh level, motion level) pairs of the first chain, by mesh level then motion level, for --grid.
std::vector<std::pair<int, int>> grid_cells(const crowd::Asset& asset) {
  std::vector<std::pair<int, int>> cells;
  for (const crowd::Level& level : asset.chains.front().levels) {
    const std::pair<int, int> cell(level.mesh_level, level.motion_level);
    if (std::find(cells.begin(), cells.end(), cell) == cells.end()) cells.push_back(cell);
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

}  // namespace

int run(int argc, char** argv);

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    return fail(1, "out of memory (fewer characters, or a smaller chain?)");
  } catch (const std::exception& error) {
    return fail(1, std::string("unexpected failure: ") + error.what());
  }
}

int run(int argc, char** argv) {
  crowd::CrowdOptions options;
  std::string error;
  if (!crowd::parse_options(argc, argv, options, error)) return error.empty() ? 0 : fail(2, error);

  const Clock::time_point load_start = Clock::now();
  std::vector<crowd::Asset> assets(options.chains.size());
  for (size_t a = 0; a < options.chains.size(); ++a) {
    if (!crowd::load_asset(options.chains[a], assets[a], error)) return fail(2, error);
    for (const std::string& warning : assets[a].warnings)
      std::fprintf(stderr, "animlod_crowd: warning: %s: %s\n", assets[a].path.c_str(), warning.c_str());
  }
  const double load_seconds = milliseconds(load_start, Clock::now()) / 1000.0;

  crowd::GlRenderer renderer;
  if (!renderer.open(options.width, options.height, options.orphan_uploads, error)) return fail(3, error);
  const crowd::CrowdScene scene(assets, options);
  crowd::CrowdAnimator animator(assets, scene, options);

  // Meshes, and the mesh id of every (asset, chain, level) bucket.
  std::vector<std::vector<std::vector<int>>> mesh_ids(assets.size());
  for (size_t a = 0; a < assets.size(); ++a) {
    int first = 0;
    if (!renderer.upload_meshes(assets[a].meshes, first, error)) return fail(2, assets[a].path + ": " + error);
    for (const crowd::Chain& chain : assets[a].chains) {
      mesh_ids[a].emplace_back();
      for (const crowd::Level& level : chain.levels) mesh_ids[a].back().push_back(first + level.mesh);
    }
  }
  std::vector<float> ground_positions;
  std::vector<uint32_t> ground_indices;
  scene.ground_mesh(ground_positions, ground_indices);
  renderer.upload_ground(ground_positions, ground_indices);
  if (!renderer.reserve(animator.max_buffer_floats(), animator.max_instances(), error)) return fail(2, error);

  // What to run: the modes, or for --grid one forced level per cell.
  std::vector<crowd::Mode> runs = options.modes;
  std::vector<std::pair<int, int>> cells;
  if (options.grid) {
    cells = grid_cells(assets.front());
    runs.assign(cells.size(), crowd::Mode());
    for (size_t c = 0; c < cells.size(); ++c)
      runs[c].name = "g" + std::to_string(cells[c].first) + "m" + std::to_string(cells[c].second);
  }

  const float fov = options.fov_degrees * 3.14159265f / 180.0f;
  const float aspect = static_cast<float>(renderer.framebuffer_width()) / static_cast<float>(renderer.framebuffer_height());
  animlod::LodCamera lod_camera;
  lod_camera.vertical_fov = fov;
  lod_camera.viewport_height = static_cast<float>(renderer.framebuffer_height());
  std::vector<crowd::ModeResult> results(runs.size());
  std::vector<int> bucket_meshes;
  // Plays run `run` over measured frames [begin, end) of the path after --warmup unmeasured ones;
  // `measure` false plays the warm-up frames only. False with `error` set when a screenshot fails.
  const auto play = [&](size_t run, int begin, int end, bool measure) {
    const crowd::Mode& mode = runs[run];
    int forced[2] = {0, 0};
    if (options.grid) forced[0] = cells[run].first, forced[1] = cells[run].second;
    animator.start(mode, options.grid ? forced : nullptr);
    crowd::ModeResult& result = results[run];
    result.name = mode.name;
    if (options.grid) result.mesh_level = forced[0], result.motion_level = forced[1];
    const size_t first_measured = result.frame_ms.size();
    Clock::time_point previous_end = Clock::now();
    for (int f = 0; f < options.warmup + (measure ? end - begin : 0); ++f) {
      const bool measured = f >= options.warmup;
      const int m = begin + std::max(f - options.warmup, 0);  // measured frame index along the path
      const float u = options.grid ? 0.5f : static_cast<float>(m) / static_cast<float>(std::max(options.frames - 1, 1));
      const crowd::Camera camera = scene.camera(options.grid ? crowd::CameraPath::nav2 : options.path, u, aspect, fov);
      lod_camera.position = camera.eye;
      const int frame = begin + f;  // animation clock: 1/30 s per frame, warm-up frames included
      const float time = static_cast<float>(frame) / 30.0f;

      const Clock::time_point t0 = Clock::now();
      crowd::FrameCounts counts;
      animator.animate(camera, lod_camera, static_cast<uint64_t>(frame), time, counts);
      const Clock::time_point t1 = Clock::now();
      float* buffer = renderer.begin_palettes();
      crowd::InstanceGpu* instance_data = renderer.begin_instances();
      const crowd::Gathered gathered = animator.gather(buffer, instance_data);
      renderer.end_uploads(gathered.floats);
      const Clock::time_point t2 = Clock::now();
      bucket_meshes.clear();
      for (const crowd::Bucket& bucket : animator.buckets())
        bucket_meshes.push_back(mesh_ids[static_cast<size_t>(bucket.asset)][static_cast<size_t>(bucket.chain)]
                                        [static_cast<size_t>(bucket.level)]);
      renderer.draw(camera.projection * camera.view, animator.buckets(), bucket_meshes, options.level_colors);
      const Clock::time_point t3 = Clock::now();
      // A screenshot's frame is taken out of every mode's timings (read back in the first mode's
      // run only), so that the modes compare the same frames.
      bool shot = false;
      for (const auto& screenshot : options.screenshots)
        if (measured && screenshot.first == m) {
          if (run == 0 && !renderer.screenshot(screenshot.second, error)) return false;
          shot = true;
        }
      renderer.swap();
      const Clock::time_point t4 = Clock::now();
      const double gpu = renderer.poll_gpu_ms();
      if (measured && !shot) {  // a frame that read back a screenshot is not timed
        result.frame_ms.push_back(milliseconds(previous_end, t4));
        result.animation_ms.push_back(milliseconds(t0, t1));
        result.upload_ms.push_back(milliseconds(t1, t2));
        result.submit_ms.push_back(milliseconds(t2, t3));
        result.swap_ms.push_back(milliseconds(t3, t4));
        if (gpu >= 0.0) result.gpu_ms.push_back(gpu);
        result.add(counts, animator.buckets().size(), gathered.matrices);
      }
      previous_end = Clock::now();
    }
    if (!measure) return true;
    double sum = 0.0;
    for (size_t i = first_measured; i < result.frame_ms.size(); ++i) sum += result.frame_ms[i];
    const double fps = sum > 0.0 ? 1000.0 * static_cast<double>(result.frame_ms.size() - first_measured) / sum
                                 : std::numeric_limits<double>::quiet_NaN();  // nothing timed: no FPS (null)
    result.round_fps.push_back(fps);
    return true;
  };
  // Every mode plays its warm-up once before the first round: the first frames of a process pay
  // for lazy shader compilation, first-touched buffers and the renderer's threads starting, which
  // a per-mode warm-up of the first mode alone did not absorb (a one-level chain's Original, the
  // same work as every other mode, measured at half their FPS).
  for (size_t run = 0; run < runs.size(); ++run)
    if (!play(run, 0, 0, false)) return fail(1, error);
  // Rounds: segment r of the path is measured in every mode before segment r + 1, so that a
  // change in machine load during the run hits every mode alike.
  for (int round = 0; round < options.rounds; ++round) {
    const int begin = crowd::round_begin(options, round), end = crowd::round_begin(options, round + 1);
    for (size_t run = 0; run < runs.size(); ++run) {
      if (!play(run, begin, end, true)) return fail(1, error);
      std::fprintf(stderr, "animlod_crowd: round %d/%d %s: %.2f fps\n", round + 1, options.rounds,
                   results[run].name.c_str(), results[run].round_fps.back());
    }
  }

  crowd::RunInfo info;
  info.renderer = renderer.renderer();
  info.gl_version = renderer.version();
  info.persistent_mapping = renderer.persistent_mapping();
  info.timer_queries = renderer.timer_queries();
  info.width = renderer.framebuffer_width();
  info.height = renderer.framebuffer_height();
  info.options = &options;
  info.assets = &assets;
  info.load_seconds = load_seconds;
  std::fputs(crowd::markdown_report(info, results).c_str(), stdout);
  if (!options.json_path.empty() && !crowd::write_atomically(options.json_path, crowd::json_report(info, results)))
    return fail(1, options.json_path + ": cannot write the JSON report");
  return 0;
}
