// The crowd report where nothing was measured: no FPS made up (null in the JSON, "-" in the table).
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "crowd_report.hpp"

TEST_CASE("crowd report: a mode without a measured frame reports no FPS") {
  crowd::CrowdOptions options;
  const std::vector<crowd::Asset> assets;
  crowd::RunInfo info;
  info.options = &options;
  info.assets = &assets;
  std::vector<crowd::ModeResult> results(2);
  results[0].name = "Original";
  results[1].name = "GLoD";
  results[1].frame_ms = {20.0, 30.0};
  results[1].drawn = 8;
  const std::string json = crowd::json_report(info, results);
  CHECK(json.find("\"Original\": {\"fps\": null, \"speedup\": null, \"frame_ms_mean\": null") != std::string::npos);
  CHECK(json.find("\"drawn\": null") != std::string::npos);
  CHECK(json.find("\"GLoD\": {\"fps\": 40, \"speedup\": null") != std::string::npos);
  CHECK(json.find("\"drawn\": 4,") != std::string::npos);
  CHECK(json.find("e+12") == std::string::npos);  // 1000 / max(mean of nothing, 1e-9) before
  const std::string table = crowd::markdown_report(info, results);
  CHECK(table.find("| Original | - | - | - | - | - | - |") != std::string::npos);
  CHECK(table.find("| GLoD | 40.00 | - | - | 25.0 |") != std::string::npos);
}
