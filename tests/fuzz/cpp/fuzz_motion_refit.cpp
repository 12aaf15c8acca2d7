// Fuzz harness: the motion LoD re-fit of motion_refit.hpp (the problem arrays Python builds, the
// objective, constraints and the SLSQP solve over a clip). Input (little-endian):
//   u8  flags       bit 0: raw float32 positions (NaN and inf possible), else int16 / 64;
//                   bit 1: hard constraints; bit 2: warm start; bit 3: precondition;
//                   bit 4: eliminate points; bit 5: cold starts given; bit 6: solve;
//                   bit 7: a fallback of its own (else the original positions)
//   u8  points      P = value % 17 (0 and 1 are invalid)
//   u8  frames      T = 1 + value % 4
//   u8  Np, Np pairs (2 FuzzInput::index over P each), Np key lengths (u8: 0 -> 0, 255 -> NaN,
//                   else value / 32); Np = value % 24
//   u8  Nc, Nc pairs; Nc = value % 4
//   u8  Nh, Nh quads, Nh key volumes (int8 / 8: 0 is invalid); Nh = value % 4
//   u8  Na, Na triples, Na key cosines (int8: -128 -> NaN, else value / 120, beyond 1 invalid);
//                   Na = value % 8
//   u8 x 3          weights alpha, beta, gamma: value / 64, 255 -> NaN
//   u8              length scale value / 16 (0 is invalid)
//   u8 x 2          max evaluations 1 + value % 40, chunk frames 1 + value % 4
//   T * P * 3 original positions, [T * P * 3 fallback], [T * P * 3 cold starts] (their roots
//   are set to the original's, as the callers' are)
// Invariants: an error has a message; on success every output has its documented size, the
// re-fitted positions are finite with the root at its original position, failures are ordered
// by frame, and the solve gives the same result with 1 and 2 threads (documented determinism).
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "animlod/motion_refit.hpp"
#include "fuzz_input.hpp"

namespace {

using animlod::fuzz::FuzzInput;

std::vector<int32_t> take_indices(FuzzInput& in, size_t rows, size_t width, size_t points) {
  std::vector<int32_t> out(rows * width);
  for (int32_t& index : out) index = in.index(points);
  return out;
}

const int32_t* data_or_null(const std::vector<int32_t>& v) { return v.empty() ? nullptr : v.data(); }
const double* data_or_null(const std::vector<double>& v) { return v.empty() ? nullptr : v.data(); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzInput in(data, size);
  const uint8_t flags = in.take<uint8_t>();
  const bool raw = in.flag(flags, 0);
  const size_t point_count = in.take<uint8_t>() % 17;
  const size_t frame_count = 1 + in.take<uint8_t>() % 4;
  const size_t points = point_count ? point_count : 1;  // index() needs a set to draw from

  animlod::MotionRefitProblem problem;
  problem.point_count = point_count;
  const size_t np = in.take<uint8_t>() % 24;
  const std::vector<int32_t> length_pairs = take_indices(in, np, 2, points);
  std::vector<double> key_lengths(np);
  for (double& length : key_lengths) {
    const uint8_t value = in.take<uint8_t>();
    length = value == 255 ? std::numeric_limits<double>::quiet_NaN() : value / 32.0;
  }
  const size_t nc = in.take<uint8_t>() % 4;
  const std::vector<int32_t> coincident_pairs = take_indices(in, nc, 2, points);
  const size_t nh = in.take<uint8_t>() % 4;
  const std::vector<int32_t> handed_quads = take_indices(in, nh, 4, points);
  std::vector<double> key_volumes(nh);
  for (double& volume : key_volumes) volume = in.take<int8_t>() / 8.0;
  const size_t na = in.take<uint8_t>() % 8;
  const std::vector<int32_t> angle_triples = take_indices(in, na, 3, points);
  std::vector<double> key_cosines(na);
  for (double& cosine : key_cosines) {
    const int8_t value = in.take<int8_t>();
    cosine = value == -128 ? std::numeric_limits<double>::quiet_NaN() : value / 120.0;
  }
  double* weights[3] = {&problem.distance_weight, &problem.string_weight, &problem.angle_weight};
  for (double* weight : weights) {
    const uint8_t value = in.take<uint8_t>();
    *weight = value == 255 ? std::numeric_limits<double>::quiet_NaN() : value / 64.0;
  }
  problem.length_scale = in.take<uint8_t>() / 16.0;
  problem.length_pairs = data_or_null(length_pairs);
  problem.key_lengths = data_or_null(key_lengths);
  problem.length_pair_count = np;
  problem.coincident_pairs = data_or_null(coincident_pairs);
  problem.coincident_pair_count = nc;
  problem.handed_quads = data_or_null(handed_quads);
  problem.key_volumes = data_or_null(key_volumes);
  problem.handed_quad_count = nh;
  problem.angle_triples = data_or_null(angle_triples);
  problem.key_cosines = data_or_null(key_cosines);
  problem.angle_triple_count = na;

  animlod::MotionRefitOptions options;
  options.hard_constraints = in.flag(flags, 1);
  options.warm_start = in.flag(flags, 2);
  options.precondition = in.flag(flags, 3);
  options.eliminate_points = in.flag(flags, 4);
  options.max_evaluations = 1 + in.take<uint8_t>() % 40;
  options.chunk_frames = 1 + in.take<uint8_t>() % 4;
  options.threads = 1;

  const size_t stride = 3 * points;
  std::vector<double> original(frame_count * stride), fallback, cold;
  for (double& value : original) value = in.coordinate(raw);
  fallback = original;
  if (in.flag(flags, 7))
    for (double& value : fallback) value = in.coordinate(raw);
  if (in.flag(flags, 5)) {
    cold.resize(original.size());
    for (double& value : cold) value = in.coordinate(raw);
  }
  for (size_t t = 0; t < frame_count; ++t)
    for (int k = 0; k < 3; ++k) {
      fallback[t * stride + k] = original[t * stride + k];
      if (!cold.empty()) cold[t * stride + k] = original[t * stride + k];
    }

  // Flat quads last, so that inputs written before they existed decode as they did.
  const size_t nf = in.take<uint8_t>() % 4;
  const std::vector<int32_t> flat_quads = take_indices(in, nf, 4, points);
  std::vector<double> flat_volumes(nf), flat_areas(nf);
  for (size_t k = 0; k < nf; ++k) {
    flat_volumes[k] = in.take<int8_t>() / 8.0;
    flat_areas[k] = in.take<int8_t>() / 16.0;  // zero or negative: refused
  }
  problem.flat_quads = data_or_null(flat_quads);
  problem.flat_volumes = data_or_null(flat_volumes);
  problem.flat_areas = data_or_null(flat_areas);
  problem.flat_quad_count = nf;

  const animlod::Status valid = animlod::validate_motion_refit_problem(problem);
  if (!valid) ANIMLOD_FUZZ_REQUIRE(!valid.message.empty());

  // The terms at the fallback positions: errors exactly when the problem is invalid.
  std::vector<double> values(frame_count), gradient(frame_count * stride);
  animlod::Status status =
      animlod::motion_refit_objective(problem, fallback.data(), original.data(), frame_count, values.data(), gradient.data());
  ANIMLOD_FUZZ_REQUIRE(status.ok == valid.ok);
  const size_t m = valid ? animlod::motion_refit_equality_count(problem) : 0;
  std::vector<double> equalities(frame_count * m), jacobian(frame_count * m * stride);
  status = animlod::motion_refit_equalities(problem, fallback.data(), frame_count, equalities.data(), jacobian.data());
  ANIMLOD_FUZZ_REQUIRE(status.ok == valid.ok);
  std::vector<double> handedness(frame_count * nh), handed_jacobian(frame_count * nh * stride);
  status = animlod::motion_refit_handedness(problem, fallback.data(), frame_count, handedness.data(),
                                            handed_jacobian.data());
  ANIMLOD_FUZZ_REQUIRE(status.ok == valid.ok);
  if (!valid || !in.flag(flags, 6)) return 0;

  animlod::MotionRefitResult result;
  status = animlod::motion_refit_solve(problem, original.data(), fallback.data(), cold.empty() ? nullptr : cold.data(),
                                       frame_count, options, result);
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
    return 0;
  }
  ANIMLOD_FUZZ_REQUIRE(result.positions.size() == frame_count * stride);
  ANIMLOD_FUZZ_REQUIRE(result.values.size() == frame_count && result.evaluations.size() == frame_count);
  for (double value : result.positions) ANIMLOD_FUZZ_REQUIRE(std::isfinite(value));
  for (size_t t = 0; t < frame_count; ++t)
    ANIMLOD_FUZZ_REQUIRE(std::memcmp(&result.positions[t * stride], &original[t * stride], 3 * sizeof(double)) == 0);
  for (size_t i = 0; i < result.failures.size(); ++i) {
    ANIMLOD_FUZZ_REQUIRE(result.failures[i].frame >= 0 && static_cast<size_t>(result.failures[i].frame) < frame_count);
    ANIMLOD_FUZZ_REQUIRE(i == 0 || result.failures[i - 1].frame < result.failures[i].frame);
    ANIMLOD_FUZZ_REQUIRE(!result.failures[i].reason.empty());
  }
  if (frame_count > static_cast<size_t>(options.chunk_frames)) {
    animlod::MotionRefitResult threaded;
    options.threads = 2;
    status = animlod::motion_refit_solve(problem, original.data(), fallback.data(), cold.empty() ? nullptr : cold.data(),
                                         frame_count, options, threaded);
    ANIMLOD_FUZZ_REQUIRE(status.ok);
    ANIMLOD_FUZZ_REQUIRE(std::memcmp(threaded.positions.data(), result.positions.data(),
                                     result.positions.size() * sizeof(double)) == 0);
    ANIMLOD_FUZZ_REQUIRE(threaded.failures.size() == result.failures.size());
  }
  return 0;
}
