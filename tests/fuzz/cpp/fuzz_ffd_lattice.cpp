// Fuzz harness: the FFD lattices of ffd_lattice.hpp (local coordinates, evaluation, the runtime
// displacement of several lattices, the least-squares fit), as face_lod and the bindings call
// them. Input (little-endian):
//   u8  flags       bit 0: raw float32 numbers (NaN and inf possible), else int16 / 64;
//                   bit 1: weights given; bit 2: a prior for the fit; bit 3: no regularisation
//   u8 x 3          lattice size l, m, n = value % 18 (0, 1 and 17 are invalid)
//   u16 points      V = 1 + value % 512, lowered to what the bytes left can fill
//   3 + 9 numbers   the box: origin, then the axes S, T, U
//   V * 3 numbers   points
//   l m n weights   (when given) u8 each: 0 -> 0, 255 -> NaN, 254 -> -1, 253 -> inf, else value / 32
//   l m n * 3       control points
//   u8  lattices    R = 1 + value % 3 for ffd_displace, each with u8 x 3 sizes as above, then
//                   u8 frames F = 1 + value % 4, V vertex lattices (FuzzInput::index over R),
//                   F * C * 3 displacements
//   u8 x 3          fit sizes 2 + value % 3 (at most 64 control points: the fit is a dense solve)
//   u8 x 2          smoothness, ridge: value / 64, 255 -> NaN, 254 -> -1
//   V * 3 targets, [fit control points * 3 prior]
// Invariants: an error has a message; in int16 mode local coordinates, evaluations and fits of
// accepted input are finite; the regular lattice of the unit box with unit weights reproduces
// its (clamped) local coordinates (linear precision); a vertex outside every lattice keeps its
// rest position exactly.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "animlod/ffd_lattice.hpp"
#include "fuzz_input.hpp"

namespace {

using animlod::fuzz::FuzzInput;

double weight(uint8_t value) {
  switch (value) {
    case 0: return 0.0;
    case 255: return std::numeric_limits<double>::quiet_NaN();
    case 254: return -1.0;
    case 253: return std::numeric_limits<double>::infinity();
    default: return value / 32.0;
  }
}

double option(uint8_t value) {
  return value == 255 ? std::numeric_limits<double>::quiet_NaN() : value == 254 ? -1.0 : value / 64.0;
}

bool valid_size(const size_t size[3]) {
  for (int a = 0; a < 3; ++a)
    if (size[a] < 2 || size[a] > animlod::kMaxLatticeSize) return false;
  return true;
}

bool all_finite(const std::vector<float>& values) {
  return std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzInput in(data, size);
  const uint8_t flags = in.take<uint8_t>();
  const bool raw = in.flag(flags, 0), with_weights = in.flag(flags, 1), with_prior = in.flag(flags, 2);
  const size_t coordinate_bytes = raw ? 4 : 2;
  animlod::LatticeView lattice;
  for (size_t& s : lattice.size) s = in.take<uint8_t>() % 18;
  size_t point_count = 1 + in.take<uint16_t>() % 512;
  const size_t fit = in.remaining() / (3 * coordinate_bytes);
  if (point_count > fit) point_count = fit ? fit : 1;

  animlod::LatticeBox box;
  for (double& value : box.origin) value = in.coordinate(raw);
  for (auto& axis : box.axes)
    for (double& value : axis) value = in.coordinate(raw);
  std::vector<float> points(3 * point_count), local(3 * point_count), out(3 * point_count);
  for (float& value : points) value = in.coordinate(raw);
  const size_t controls = valid_size(lattice.size) ? lattice.size[0] * lattice.size[1] * lattice.size[2] : 0;
  std::vector<double> weights(with_weights ? controls : 0), control_points(3 * controls);
  for (double& value : weights) value = weight(in.take<uint8_t>());
  for (double& value : control_points) value = in.coordinate(raw);
  bool weights_valid = true;
  for (double w : weights) weights_valid = weights_valid && std::isfinite(w) && w > 0.0;

  // Local coordinates; on error the points themselves / 64 stand in (any local values will do).
  animlod::Status status = animlod::ffd_local_coordinates(box, points.data(), point_count, local.data());
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
    for (size_t i = 0; i < points.size(); ++i) local[i] = points[i] / 64.0f;
  } else if (!raw) {
    ANIMLOD_FUZZ_REQUIRE(all_finite(local));
  }

  // Evaluation of the decoded lattice.
  lattice.control_points = control_points.empty() ? nullptr : control_points.data();
  lattice.weights = with_weights && controls ? weights.data() : nullptr;
  status = animlod::ffd_evaluate(lattice, local.data(), point_count, out.data());
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
  } else {
    ANIMLOD_FUZZ_REQUIRE(controls > 0 && weights_valid && all_finite(local));
    if (!raw) ANIMLOD_FUZZ_REQUIRE(all_finite(out));
  }
  // Linear precision: the regular lattice of the unit box with unit weights is the identity on
  // the box (points outside move as the nearest point of the box).
  if (controls && all_finite(local)) {
    std::vector<double> regular(3 * controls);
    for (size_t i = 0, c = 0; i < lattice.size[0]; ++i)
      for (size_t j = 0; j < lattice.size[1]; ++j)
        for (size_t k = 0; k < lattice.size[2]; ++k, ++c) {
          regular[3 * c] = static_cast<double>(i) / static_cast<double>(lattice.size[0] - 1);
          regular[3 * c + 1] = static_cast<double>(j) / static_cast<double>(lattice.size[1] - 1);
          regular[3 * c + 2] = static_cast<double>(k) / static_cast<double>(lattice.size[2] - 1);
        }
    const animlod::LatticeView identity{{lattice.size[0], lattice.size[1], lattice.size[2]}, regular.data(), nullptr};
    ANIMLOD_FUZZ_REQUIRE(animlod::ffd_evaluate(identity, local.data(), point_count, out.data()).ok);
    for (size_t i = 0; i < out.size(); ++i)
      ANIMLOD_FUZZ_REQUIRE(std::fabs(out[i] - std::clamp(local[i], 0.0f, 1.0f)) < 1e-4f);
  }

  // The runtime displacement of several lattices.
  const size_t lattice_count = 1 + in.take<uint8_t>() % 3;
  std::vector<int32_t> sizes(3 * lattice_count);
  size_t total = 0;
  bool sizes_valid = true;
  for (size_t r = 0; r < lattice_count; ++r) {
    size_t s[3];
    for (int a = 0; a < 3; ++a) s[a] = in.take<uint8_t>() % 18, sizes[3 * r + a] = static_cast<int32_t>(s[a]);
    sizes_valid = sizes_valid && valid_size(s);
    if (valid_size(s)) total += s[0] * s[1] * s[2];
  }
  const size_t frame_count = 1 + in.take<uint8_t>() % 4;
  std::vector<int32_t> vertex_lattice(point_count);
  for (int32_t& r : vertex_lattice) r = in.index(lattice_count);
  std::vector<double> displacements(3 * frame_count * total);
  for (double& value : displacements) value = in.coordinate(raw);
  std::vector<double> set_weights(total, 1.0);
  for (size_t c = 0; with_weights && c < total; ++c) set_weights[c] = weight(in.take<uint8_t>());
  animlod::LatticeSetView set;
  set.lattice_count = lattice_count;
  set.sizes = sizes.data();
  set.displacements = displacements.empty() ? nullptr : displacements.data();
  set.weights = with_weights ? set_weights.data() : nullptr;
  set.frame_count = frame_count;
  std::vector<float> moved(frame_count * 3 * point_count);
  status = animlod::ffd_displace(set, points.data(), local.data(), vertex_lattice.data(), point_count, moved.data());
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
  } else {
    ANIMLOD_FUZZ_REQUIRE(sizes_valid);
    for (size_t v = 0; v < point_count; ++v) {
      ANIMLOD_FUZZ_REQUIRE(vertex_lattice[v] >= -1 && vertex_lattice[v] < static_cast<int32_t>(lattice_count));
      if (vertex_lattice[v] < 0)
        for (size_t f = 0; f < frame_count; ++f)
          ANIMLOD_FUZZ_REQUIRE(std::memcmp(&moved[3 * (f * point_count + v)], &points[3 * v], 3 * sizeof(float)) == 0);
    }
  }

  // The least-squares fit on a small lattice.
  const size_t fit_size[3] = {2 + in.take<uint8_t>() % 3u, 2 + in.take<uint8_t>() % 3u, 2 + in.take<uint8_t>() % 3u};
  const size_t fit_controls = fit_size[0] * fit_size[1] * fit_size[2];
  animlod::FfdFitOptions options;
  options.smoothness = option(in.take<uint8_t>());
  options.ridge = option(in.take<uint8_t>());
  if (in.flag(flags, 3)) options.smoothness = options.ridge = 0.0;
  std::vector<float> targets(3 * point_count);
  for (float& value : targets) value = in.coordinate(raw);
  std::vector<double> prior(with_prior ? 3 * fit_controls : 0), fitted(3 * fit_controls);
  for (double& value : prior) value = in.coordinate(raw);
  std::vector<double> fit_weights(fit_controls, 1.0);
  for (size_t c = 0; with_weights && c < fit_controls; ++c) fit_weights[c] = weight(in.take<uint8_t>());
  status = animlod::ffd_fit(fit_size, with_weights ? fit_weights.data() : nullptr, local.data(), targets.data(),
                            point_count, with_prior ? prior.data() : nullptr, fitted.data(), options);
  if (!status) {
    ANIMLOD_FUZZ_REQUIRE(!status.message.empty());
  } else if (!raw) {
    // Bounded weights, targets and local coordinates (clamped): a regularised or least-norm
    // solution is finite.
    for (double value : fitted) ANIMLOD_FUZZ_REQUIRE(std::isfinite(value));
  }
  return 0;
}
