// Command-line checks of animlod_crowd that need no GL context and no file: every mistake is
// refused up front with one line naming the option.
#include <doctest/doctest.h>

#include <initializer_list>
#include <string>
#include <vector>

#include "crowd_options.hpp"

namespace {

// parse_options over `arguments` (after the program name); the error, empty when accepted.
std::string parse(std::initializer_list<const char*> arguments) {
  std::vector<std::string> words{"animlod_crowd"};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  crowd::CrowdOptions options;
  std::string error;
  const bool accepted = crowd::parse_options(static_cast<int>(argv.size()), argv.data(), options, error);
  CHECK(accepted == error.empty());
  return error;
}

}  // namespace

TEST_CASE("crowd options: screenshots that leave a round no frame to time are refused") {
  // Screenshot frames are left out of the timings: a round made of them measured nothing and
  // reported 1e12 FPS over 0 frames.
  std::string error = parse({"a.glb", "--frames", "1", "--screenshot", "0", "x.png"});
  CHECK(error.find("--screenshot: takes every measured frame (--frames 1)") == 0);
  error = parse({"a.glb", "--frames", "4", "--rounds", "2", "--screenshot", "2", "x.png", "--screenshot", "3", "y.png"});
  CHECK(error.find("--screenshot: takes every measured frame of round 2 (frames 2 to 3 of --frames 4 --rounds 2)") == 0);
  error = parse({"a.glb", "--frames", "3", "--screenshot", "1", "x.png", "--screenshot", "1", "y.png", "--screenshot", "0", "z.png"});
  CHECK(error.empty());  // frame 2 is timed
  error = parse({"a.glb", "--frames", "4", "--rounds", "2", "--screenshot", "1", "x.png", "--screenshot", "2", "y.png"});
  CHECK(error.empty());  // one timed frame in each round
}

TEST_CASE("crowd options: an integer out of range is refused with the range it takes") {
  CHECK(parse({"a.glb", "--frames", "2000000000"}) == "--frames: expected an integer from 1 to 1000000000, got '2000000000'");
  CHECK(parse({"a.glb", "--warmup", "-1"}) == "--warmup: expected an integer from 0 to 1000000000, got '-1'");
  CHECK(parse({"a.glb", "--modes", ""}) == "--modes: no mode given");
}

TEST_CASE("crowd options: an empty item in a list is refused") {
  // "Original," ran Original alone: the trailing empty item was dropped unseen.
  CHECK(parse({"a.glb", "--modes", "Original,"}) == "--modes: empty item in 'Original,' (a comma too many?)");
  CHECK(parse({"a.glb", "--modes", ",GLoD"}) == "--modes: empty item in ',GLoD' (a comma too many?)");
  CHECK(parse({"a.glb", "--modes", "Original,,GLoD"}) == "--modes: empty item in 'Original,,GLoD' (a comma too many?)");
  CHECK(parse({"a.glb", "--modes", "Original,GLoD+skip"}).empty());
}
