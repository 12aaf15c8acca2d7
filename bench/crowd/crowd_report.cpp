// The report of a crowd run. JSON is written by hand: the output is a flat document of numbers
// and a few strings, and no JSON library ships with Debian's tinygltf (third_party_notes.md).
#include "crowd_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <sstream>

namespace crowd {

namespace {

// What was not measured: null in the JSON, "-" in the table, never a number made up.
constexpr double kNotMeasured = std::numeric_limits<double>::quiet_NaN();

double mean(const std::vector<double>& values) {
  return values.empty() ? kNotMeasured
                        : std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
}

// Linear-interpolated percentile (numpy's default).
double percentile(std::vector<double> values, double p) {
  if (values.empty()) return kNotMeasured;
  std::sort(values.begin(), values.end());
  const double at = p / 100.0 * static_cast<double>(values.size() - 1);
  const size_t low = static_cast<size_t>(at);
  const size_t high = std::min(low + 1, values.size() - 1);
  return values[low] + (at - static_cast<double>(low)) * (values[high] - values[low]);
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\', out += c;
    else if (static_cast<unsigned char>(c) < 0x20) {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\u%04x", c);
      out += escape;
    } else out += c;
  }
  return out + "\"";
}

std::string number(double value) {
  if (!std::isfinite(value)) return "null";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

// `value` with `decimals` decimals and `suffix` for the table, "-" where nothing was measured.
std::string fixed(double value, int decimals, const char* suffix = "") {
  if (!std::isfinite(value)) return "-";
  char text[48];
  std::snprintf(text, sizeof text, "%.*f%s", decimals, value, suffix);
  return text;
}

// The mode every speed-up is measured against: Original without frame skipping.
const ModeResult* original_of(const std::vector<ModeResult>& results) {
  for (const ModeResult& r : results)
    if (r.name == "Original") return &r;
  return nullptr;
}

double fps(const ModeResult& r) { return 1000.0 / mean(r.frame_ms); }

// A sum over the measured frames, per frame.
double per_frame(double sum, const ModeResult& r) {
  return r.frame_ms.empty() ? kNotMeasured : sum / static_cast<double>(r.frame_ms.size());
}

// Speed-up over `base` in each round (the modes took turns on the same path segment).
std::vector<double> round_speedups(const ModeResult& r, const ModeResult& base) {
  std::vector<double> out;
  for (size_t k = 0; k < r.round_fps.size() && k < base.round_fps.size(); ++k)
    out.push_back(base.round_fps[k] > 0.0 ? r.round_fps[k] / base.round_fps[k] : kNotMeasured);
  return out;
}

// True when `r` drew, animated and uploaded exactly what `base` did on the same frames: a mode
// whose LoD has nothing to choose from (a one-level chain), whose speed-up is then the spread of
// the measurement alone.
bool same_work(const ModeResult& r, const ModeResult& base) {
  return r.frame_ms.size() == base.frame_ms.size() && r.drawn == base.drawn && r.triangles == base.triangles &&
         r.joints == base.joints && r.palette_joints == base.palette_joints && r.updates == base.updates &&
         r.draw_calls == base.draw_calls;
}

}  // namespace

void ModeResult::add(const FrameCounts& counts, size_t buckets, size_t palette_joints_uploaded) {
  drawn += counts.drawn;
  triangles += static_cast<double>(counts.triangles);
  joints += static_cast<double>(counts.joints);
  palette_joints += static_cast<double>(palette_joints_uploaded);
  updates += counts.updates;
  draw_calls += static_cast<double>(buckets);
  for (size_t l = 0; l < levels.size() && l < counts.levels.size(); ++l) levels[l] += counts.levels[l];
}

std::string markdown_report(const RunInfo& info, const std::vector<ModeResult>& results) {
  const CrowdOptions& options = *info.options;
  std::ostringstream out;
  out << "renderer: " << info.renderer << " (OpenGL " << info.gl_version << "; palettes "
      << (info.persistent_mapping ? "persistent-mapped" : "orphaned") << "; GPU timer queries "
      << (info.timer_queries ? "yes" : "no") << ")\n";
  out << options.count << " characters, " << info.width << "x" << info.height << ", path " << path_name(options.path)
      << ", " << options.frames << " measured frames per " << (options.grid ? "cell" : "mode") << "\n";
  for (const Asset& asset : *info.assets) {
    out << asset.path << ":";
    for (const Chain& chain : asset.chains) {
      out << " [" << chain.name << ":";
      for (size_t l = 0; l < chain.levels.size(); ++l) {
        const Level& level = chain.levels[l];
        if (l == chain.selection_count) out << " | grid:";
        out << " g" << level.mesh_level << "m" << level.motion_level << " "
            << asset.meshes[static_cast<size_t>(level.mesh)].triangle_count() << "t/"
            << asset.rigs[static_cast<size_t>(level.rig)].joint_count() << "j";
      }
      out << "]";
    }
    out << " clips:";
    for (const std::string& name : asset.clip_names) out << " " << name;
    out << "\n";
  }
  out << "\n";
  if (options.grid) {
    out << "| mesh level | motion level | triangles / frame | joints / frame | FPS | frame ms p50 |\n";
    out << "|---:|---:|---:|---:|---:|---:|\n";
  } else {
    out << "| mode | FPS | speed-up | per round | frame ms p50 | p95 | drawn | triangles | joints animated | "
           "palette joints | CPU anim ms | upload ms | submit ms | swap ms | GPU ms |\n";
    out << "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  }
  for (const ModeResult& r : results) {
    if (options.grid) {
      out << "| " << r.mesh_level << " | " << r.motion_level << " | " << fixed(per_frame(r.triangles, r), 0) << " | "
          << fixed(per_frame(r.joints, r), 0) << " | " << fixed(fps(r), 2) << " | " << fixed(percentile(r.frame_ms, 50), 1)
          << " |\n";
      continue;
    }
    const ModeResult* base = original_of(results);
    std::string speedup = "-", range = "-";
    if (base) {
      speedup = fixed(fps(r) / fps(*base), 2, "x");
      const std::vector<double> rounds = round_speedups(r, *base);
      if (rounds.size() > 1)
        range = fixed(*std::min_element(rounds.begin(), rounds.end()), 2) + "-" +
                fixed(*std::max_element(rounds.begin(), rounds.end()), 2, "x");
    }
    out << "| " << r.name << " | " << fixed(fps(r), 2) << " | " << speedup << " | " << range << " | "
        << fixed(percentile(r.frame_ms, 50), 1) << " | " << fixed(percentile(r.frame_ms, 95), 1) << " | "
        << fixed(per_frame(r.drawn, r), 0) << " | " << fixed(per_frame(r.triangles, r), 0) << " | "
        << fixed(per_frame(r.joints, r), 0) << " | " << fixed(per_frame(r.palette_joints, r), 0) << " | "
        << fixed(mean(r.animation_ms), 2) << " | " << fixed(mean(r.upload_ms), 2) << " | " << fixed(mean(r.submit_ms), 2)
        << " | " << fixed(mean(r.swap_ms), 1) << " | " << fixed(mean(r.gpu_ms), 2) << " |\n";
  }
  const ModeResult* base = options.grid ? nullptr : original_of(results);
  std::string alike;
  for (const ModeResult& r : results)
    if (base && &r != base && same_work(r, *base)) alike += (alike.empty() ? "" : ", ") + r.name;
  if (!alike.empty())
    out << "\n" << alike << ": the same work per frame as Original (their LoD never chose another level: one-level "
        << "chains, or every character near), so their speed-ups are the spread of the measurement, not a gain.\n";
  return out.str();
}

std::string json_report(const RunInfo& info, const std::vector<ModeResult>& results) {
  const CrowdOptions& options = *info.options;
  std::ostringstream out;
  out << "{\n  \"renderer\": " << quoted(info.renderer) << ",\n  \"gl_version\": " << quoted(info.gl_version)
      << ",\n  \"palette_upload\": " << quoted(info.persistent_mapping ? "persistent" : "orphaned")
      << ",\n  \"timer_queries\": " << (info.timer_queries ? "true" : "false") << ",\n  \"count\": " << options.count
      << ",\n  \"frames\": " << options.frames << ",\n  \"warmup\": " << options.warmup << ",\n  \"rounds\": " << options.rounds << ",\n  \"width\": " << info.width
      << ",\n  \"height\": " << info.height << ",\n  \"path\": " << quoted(path_name(options.path))
      << ",\n  \"pixel_error\": " << number(options.pixel_error) << ",\n  \"hysteresis\": " << number(options.hysteresis)
      << ",\n  \"skip_full_coverage\": " << number(options.skip_full_coverage)
      << ",\n  \"skip_max_interval\": " << options.skip_max_interval << ",\n  \"seed\": " << options.seed
      << ",\n  \"load_seconds\": " << number(info.load_seconds) << ",\n  \"chains\": [";
  bool first_asset = true;
  for (const Asset& asset : *info.assets) {
    out << (first_asset ? "\n" : ",\n") << "    {\"file\": " << quoted(asset.path) << ", \"height\": " << number(asset.height())
        << ", \"clips\": [";
    for (size_t k = 0; k < asset.clip_names.size(); ++k) out << (k ? ", " : "") << quoted(asset.clip_names[k]);
    out << "], \"warnings\": [";
    for (size_t w = 0; w < asset.warnings.size(); ++w) out << (w ? ", " : "") << quoted(asset.warnings[w]);
    out << "], \"nodes\": [";
    for (size_t c = 0; c < asset.chains.size(); ++c) {
      const Chain& chain = asset.chains[c];
      out << (c ? ", " : "") << "{\"name\": " << quoted(chain.name) << ", \"levels\": [";
      for (size_t l = 0; l < chain.levels.size(); ++l) {
        const Level& level = chain.levels[l];
        out << (l ? ", " : "") << "{\"chain_level\": " << (l < chain.selection_count ? static_cast<long>(l) : -1L)
            << ", \"mesh_level\": " << level.mesh_level << ", \"motion_level\": " << level.motion_level
            << ", \"triangles\": " << asset.meshes[static_cast<size_t>(level.mesh)].triangle_count()
            << ", \"joints\": " << asset.rigs[static_cast<size_t>(level.rig)].joint_count()
            << ", \"error\": " << number(level.error) << ", \"coverage\": " << number(level.coverage) << "}";
      }
      out << "]}";
    }
    out << "]}";
    first_asset = false;
  }
  out << "\n  ],\n  \"" << (options.grid ? "grid" : "modes") << "\": " << (options.grid ? "[" : "{");
  for (size_t i = 0; i < results.size(); ++i) {
    const ModeResult& r = results[i];
    out << (i ? ",\n    " : "\n    ");
    if (!options.grid) out << quoted(r.name) << ": ";
    out << "{";
    if (options.grid) out << "\"mesh_level\": " << r.mesh_level << ", \"motion_level\": " << r.motion_level << ", ";
    const ModeResult* base = options.grid ? nullptr : original_of(results);
    out << "\"fps\": " << number(fps(r)) << ", \"speedup\": " << (base ? number(fps(r) / fps(*base)) : "null")
        << ", \"frame_ms_mean\": " << number(mean(r.frame_ms)) << ", \"frame_ms_p50\": " << number(percentile(r.frame_ms, 50))
        << ", \"frame_ms_p95\": " << number(percentile(r.frame_ms, 95)) << ", \"drawn\": " << number(per_frame(r.drawn, r))
        << ", \"triangles\": " << number(per_frame(r.triangles, r)) << ", \"joints\": " << number(per_frame(r.joints, r))
        << ", \"palette_joints\": " << number(per_frame(r.palette_joints, r))
        << ", \"pose_updates\": " << number(per_frame(r.updates, r))
        << ", \"draw_calls\": " << number(per_frame(r.draw_calls, r)) << ", \"cpu_animation_ms\": " << number(mean(r.animation_ms))
        << ", \"upload_ms\": " << number(mean(r.upload_ms)) << ", \"submit_ms\": " << number(mean(r.submit_ms))
        << ", \"swap_ms\": " << number(mean(r.swap_ms))
        << ", \"gpu_ms\": " << number(mean(r.gpu_ms)) << ", \"measured_frames\": " << r.frame_ms.size()
        << ", \"same_work_as_original\": " << (base && &r != base && same_work(r, *base) ? "true" : "false") << ", \"round_fps\": [";
    for (size_t k = 0; k < r.round_fps.size(); ++k) out << (k ? ", " : "") << number(r.round_fps[k]);
    out << "], \"round_speedups\": [";
    if (base) {
      const std::vector<double> rounds = round_speedups(r, *base);
      for (size_t k = 0; k < rounds.size(); ++k) out << (k ? ", " : "") << number(rounds[k]);
    }
    out << "], \"levels\": [";
    size_t last = 0;
    for (size_t l = 0; l < r.levels.size(); ++l)
      if (r.levels[l] > 0) last = l + 1;
    for (size_t l = 0; l < last; ++l) out << (l ? ", " : "") << number(per_frame(r.levels[l], r));
    out << "]}";
  }
  out << "\n  " << (options.grid ? "]" : "}") << "\n}\n";
  return out.str();
}

bool write_atomically(const std::string& path, const std::string& text) {
  const std::string partial = path + ".partial";
  std::FILE* file = std::fopen(partial.c_str(), "wb");
  if (!file) return false;
  const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed || std::rename(partial.c_str(), path.c_str()) != 0) {
    std::remove(partial.c_str());
    return false;
  }
  return true;
}

}  // namespace crowd
