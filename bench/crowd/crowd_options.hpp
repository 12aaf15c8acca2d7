// Command line of animlod_crowd: what to load, how many characters, which LoD modes and camera
// path, and where the report and screenshots go.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace crowd {

// Which levels of a chain a mode may use (the paper's Table 2 columns), and whether the pose
// update rate falls with distance (frame skipping, facial LoD paper Section 4.2.3).
struct Mode {
  std::string name;           // "Original", "GLoD", "MLoD", "G+MLoD", with "+skip" for frame skipping
  bool geometry_levels = false;  // levels with mesh_level > 0 allowed
  bool motion_levels = false;    // levels with motion_level > 0 allowed
  bool frame_skipping = false;
};

// The camera's flight (deterministic in the frame index).
enum class CameraPath {
  nav1,      // through the crowd at head height (the paper's Nav1)
  nav2,      // over the crowd, looking down (the paper's Nav2)
  pullback,  // starts close in front of the crowd and backs away (levels switch on the way)
};

struct CrowdOptions {
  std::vector<std::string> chains;  // LoD GLB files; characters take them in turn
  int count = 1000;                 // characters
  int frames = 300;                 // measured frames per mode
  int warmup = 10;                  // frames before measuring, per mode and round (camera at the round's start)
  int rounds = 1;                   // the measured frames split into rounds; the modes take turns per round
  std::vector<Mode> modes;
  CameraPath path = CameraPath::nav1;
  int width = 1280, height = 720;   // window, pixels
  float fov_degrees = 50.0f;        // vertical field of view
  float pixel_error = 2.0f;         // screen-space error budget of the selector, pixels
  float hysteresis = 0.15f;         // LodSelectorOptions::hysteresis
  float skip_full_coverage = 0.25f; // AnimationRateOptions::full_rate_coverage
  int skip_max_interval = 8;        // AnimationRateOptions::max_interval
  float spacing = 1.6f;             // distance between neighbours, in character heights
  unsigned seed = 1;
  bool level_colors = false;        // tint each character by its level index
  bool grid = false;                // Fig. 1: every (mesh level, motion level) for all characters
  bool orphan_uploads = false;      // use the GL 3.3 upload path (orphaned buffers) even where
                                    // persistent mapping is available
  std::string json_path;            // write the JSON report here ("" = none)
  std::vector<std::pair<int, std::string>> screenshots;  // (measured frame of the first mode, PNG path)
};

const char* path_name(CameraPath path);

// The first measured frame of round `round` in [0, rounds]: the rounds split the frames evenly
// (round `rounds` begins past the last frame).
int round_begin(const CrowdOptions& options, int round);

// Parses argv; on a mistake returns false with `error` set to one line (and on --help returns
// false with error empty after printing the usage).
bool parse_options(int argc, char** argv, CrowdOptions& out, std::string& error);

}  // namespace crowd
