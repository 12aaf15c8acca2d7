// Command-line parsing of animlod_crowd (crowd_options.hpp): every mistake is one line.
#include "crowd_options.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <set>

namespace crowd {

namespace {

const char* kUsage = R"(usage: animlod_crowd [options] CHAIN.glb [CHAIN.glb ...]

Renders N skinned characters read from LoD GLBs (MSFT_lod chains of geometry x motion levels;
a GLB without MSFT_lod is a one-level chain) with instanced GPU skinning, flies a camera along
a path and reports frame times per LoD mode as a Markdown table (stdout) and JSON.

  --count N              characters (default 1000)
  --frames K             measured frames per mode (default 300)
  --warmup W             unmeasured frames before each mode in each round, and once more per
                         mode before the first round (default 10)
  --rounds R             split the path into R rounds and let the modes take turns on each,
                         so that a change in machine load hits every mode alike (default 1)
  --modes LIST           all, or comma-separated of Original, GLoD, MLoD, G+MLoD, each
                         optionally with +skip (frame skipping); all = the four with and
                         without +skip (default all)
  --path P               nav1 (through the crowd), nav2 (over it) or pullback (default nav1)
  --width W --height H   window size in pixels (default 1280 x 720)
  --fov DEGREES          vertical field of view (default 50)
  --pixel-error PX       screen-space error budget for choosing levels (default 2)
  --hysteresis H         relative dead band around each level threshold (default 0.15)
  --skip-full-coverage C projected height (fraction of the viewport) from which the pose
                         updates every frame with +skip (default 0.25)
  --skip-max-interval F  longest interval between pose updates with +skip (default 8)
  --spacing S            distance between characters in character heights (default 1.6)
  --seed S               placement, clips and phases (default 1)
  --level-colors         tint every character by the index of the level it shows
  --grid                 Fig. 1: every (mesh level, motion level) of the first chain forced
                         on all characters, one row per level (instead of --modes)
  --upload orphan        upload palettes through orphaned buffers (the OpenGL 3.3 path) even
                         where persistent mapping (4.4) is available
  --json FILE            write the report as JSON
  --screenshot F FILE    save measured frame F of the first mode as PNG (repeatable)
)";

// The largest count an integer option takes (frames, characters, pixels).
constexpr long kLargestInt = 1000000000L;

bool to_int(const std::string& text, int& out) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || value < -kLargestInt || value > kLargestInt) return false;
  out = static_cast<int>(value);
  return true;
}

bool to_float(const std::string& text, float& out) {
  char* end = nullptr;
  out = std::strtof(text.c_str(), &end);
  return !text.empty() && *end == '\0' && std::isfinite(out);
}

// The items of a comma-separated list, empty ones included (getline drops a trailing one:
// "Original," read as "Original").
std::vector<std::string> comma_items(const std::string& list) {
  std::vector<std::string> items;
  for (size_t begin = 0;;) {
    const size_t end = list.find(',', begin);
    items.push_back(list.substr(begin, end == std::string::npos ? std::string::npos : end - begin));
    if (end == std::string::npos) return items;
    begin = end + 1;
  }
}

bool parse_modes(const std::string& list, std::vector<Mode>& out, std::string& error) {
  out.clear();
  if (list == "all") {
    for (bool skip : {false, true})
      for (const char* base : {"Original", "GLoD", "MLoD", "G+MLoD"}) {
        std::vector<Mode> one;
        parse_modes(std::string(base) + (skip ? "+skip" : ""), one, error);
        out.push_back(one[0]);
      }
    return true;
  }
  if (list.empty()) {
    error = "--modes: no mode given";
    return false;
  }
  for (const std::string& item : comma_items(list)) {
    if (item.empty()) {
      error = "--modes: empty item in '" + list + "' (a comma too many?)";
      return false;
    }
    Mode mode;
    mode.name = item;
    std::string base = item;
    const std::string suffix = "+skip";
    if (base.size() > suffix.size() && base.compare(base.size() - suffix.size(), suffix.size(), suffix) == 0) {
      mode.frame_skipping = true;
      base.resize(base.size() - suffix.size());
    }
    if (base == "Original") {
    } else if (base == "GLoD") {
      mode.geometry_levels = true;
    } else if (base == "MLoD") {
      mode.motion_levels = true;
    } else if (base == "G+MLoD") {
      mode.geometry_levels = mode.motion_levels = true;
    } else {
      error = "--modes: unknown mode '" + item + "' (expected Original, GLoD, MLoD, G+MLoD, optionally +skip, or all)";
      return false;
    }
    out.push_back(mode);
  }
  return true;
}

}  // namespace

int round_begin(const CrowdOptions& options, int round) {
  return static_cast<int>(static_cast<int64_t>(options.frames) * round / options.rounds);
}

const char* path_name(CameraPath path) {
  switch (path) {
    case CameraPath::nav1: return "nav1";
    case CameraPath::nav2: return "nav2";
    case CameraPath::pullback: return "pullback";
  }
  return "?";
}

bool parse_options(int argc, char** argv, CrowdOptions& out, std::string& error) {
  parse_modes("all", out.modes, error);
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](std::string& into) {
      if (i + 1 >= argc) {
        error = arg + ": missing value";
        return false;
      }
      into = argv[++i];
      return true;
    };
    std::string text;
    auto int_option = [&](int& into, int lowest) {
      if (!value(text)) return false;
      if (!to_int(text, into) || into < lowest) {
        error = arg + ": expected an integer from " + std::to_string(lowest) + " to " + std::to_string(kLargestInt) +
                ", got '" + text + "'";
        return false;
      }
      return true;
    };
    auto float_option = [&](float& into, float lowest, bool strict) {
      if (!value(text)) return false;
      if (!to_float(text, into) || into < lowest || (strict && into == lowest)) {
        error = arg + ": expected a number " + (strict ? "> " : ">= ") + std::to_string(lowest) + ", got '" + text + "'";
        return false;
      }
      return true;
    };
    bool ok = true;
    if (arg == "-h" || arg == "--help") {
      std::fputs(kUsage, stdout);
      error.clear();
      return false;
    } else if (arg == "--count") {
      ok = int_option(out.count, 1);
    } else if (arg == "--frames") {
      ok = int_option(out.frames, 1);
    } else if (arg == "--warmup") {
      ok = int_option(out.warmup, 0);
    } else if (arg == "--rounds") {
      ok = int_option(out.rounds, 1);
    } else if (arg == "--width") {
      ok = int_option(out.width, 16);
    } else if (arg == "--height") {
      ok = int_option(out.height, 16);
    } else if (arg == "--seed") {
      int seed = 0;
      ok = int_option(seed, 0);
      out.seed = static_cast<unsigned>(seed);
    } else if (arg == "--skip-max-interval") {
      ok = int_option(out.skip_max_interval, 1);
    } else if (arg == "--fov") {
      ok = float_option(out.fov_degrees, 0.0f, true) && out.fov_degrees < 179.0f;
      if (ok == false && error.empty()) error = "--fov: expected degrees in (0, 179)";
    } else if (arg == "--pixel-error") {
      ok = float_option(out.pixel_error, 0.0f, true);
    } else if (arg == "--hysteresis") {
      ok = float_option(out.hysteresis, 0.0f, false);
    } else if (arg == "--skip-full-coverage") {
      ok = float_option(out.skip_full_coverage, 0.0f, true);
    } else if (arg == "--spacing") {
      ok = float_option(out.spacing, 0.0f, true);
    } else if (arg == "--modes") {
      ok = value(text) && parse_modes(text, out.modes, error);
    } else if (arg == "--path") {
      ok = value(text);
      if (ok && text == "nav1") out.path = CameraPath::nav1;
      else if (ok && text == "nav2") out.path = CameraPath::nav2;
      else if (ok && text == "pullback") out.path = CameraPath::pullback;
      else if (ok) {
        error = "--path: unknown path '" + text + "' (expected nav1, nav2 or pullback)";
        ok = false;
      }
    } else if (arg == "--level-colors") {
      out.level_colors = true;
    } else if (arg == "--grid") {
      out.grid = true;
    } else if (arg == "--upload") {
      ok = value(text);
      if (ok && text == "orphan") out.orphan_uploads = true;
      else if (ok && text != "auto") {
        error = "--upload: expected orphan or auto, got '" + text + "'";
        ok = false;
      }
    } else if (arg == "--json") {
      ok = value(out.json_path);
    } else if (arg == "--screenshot") {
      int frame = 0;
      ok = int_option(frame, 0) && value(text);
      if (ok) out.screenshots.emplace_back(frame, text);
    } else if (!arg.empty() && arg[0] == '-') {
      error = "unknown option " + arg + " (see --help)";
      ok = false;
    } else {
      out.chains.push_back(arg);
    }
    if (!ok) return false;
  }
  if (out.chains.empty()) {
    error = "no chain given: pass one or more LoD GLB files (see --help)";
    return false;
  }
  if (out.rounds > out.frames) {
    error = "--rounds: " + std::to_string(out.rounds) + " rounds for " + std::to_string(out.frames) + " measured frames";
    return false;
  }
  for (const auto& shot : out.screenshots) {
    if (shot.first >= out.frames) {
      error = "--screenshot: frame " + std::to_string(shot.first) + " is not among the " + std::to_string(out.frames) +
              " measured frames";
      return false;
    }
  }
  // A screenshot's frame is left out of every mode's timings: each round needs a frame to time,
  // or its modes would report an FPS over no frame at all.
  std::set<int> shot_frames;
  for (const auto& shot : out.screenshots) shot_frames.insert(shot.first);
  for (int frame : shot_frames) {
    int round = static_cast<int>(static_cast<int64_t>(frame) * out.rounds / out.frames);
    while (round_begin(out, round + 1) <= frame) ++round;
    while (round_begin(out, round) > frame) --round;
    const int begin = round_begin(out, round), end = round_begin(out, round + 1);
    if (std::distance(shot_frames.lower_bound(begin), shot_frames.lower_bound(end)) < end - begin) continue;
    const std::string which = out.rounds == 1 ? " (--frames " + std::to_string(out.frames) + ")"
                                              : " of round " + std::to_string(round + 1) + " (frames " + std::to_string(begin) +
                                                    " to " + std::to_string(end - 1) + " of --frames " +
                                                    std::to_string(out.frames) + " --rounds " + std::to_string(out.rounds) + ")";
    error = "--screenshot: takes every measured frame" + which +
            " out of the timings, so nothing would be measured: measure more frames or screenshot fewer";
    return false;
  }
  return true;
}

}  // namespace crowd
