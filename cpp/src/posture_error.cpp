// Eq. 1's row sums (seeds/000, Section 4; posture_error.hpp). The table is symmetric, so each
// pair of frames is measured once and added to both rows.
#include "animlod/posture_error.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "worker_threads.hpp"

namespace animlod {

namespace {

// Angle between the unit-or-zero vectors u and v. |u -+ v|^2 = |u|^2 + |v|^2 -+ 2 u.v from the
// dot product, except where the angle is tiny and that difference cancels: there |u - v| is
// taken directly (exactly 0 for identical directions).
double angle_between(const double* u, const double* v, double squared_u, double squared_v) {
  const double dot = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  const double base = squared_u + squared_v;
  const double minus = std::max(base - 2.0 * dot, 0.0);
  if (minus >= 1e-8) return 2.0 * std::atan2(std::sqrt(minus), std::sqrt(std::max(base + 2.0 * dot, 0.0)));
  double difference = 0.0, sum = 0.0;
  for (int k = 0; k < 3; ++k) {
    difference += (u[k] - v[k]) * (u[k] - v[k]);
    sum += (u[k] + v[k]) * (u[k] + v[k]);
  }
  return 2.0 * std::atan2(std::sqrt(difference), std::sqrt(sum));
}

// One bone's row (n,) of sums. The bone's directions, squared lengths and radii are first
// gathered into `scratch` (5 n), so that the pair loop reads contiguous memory.
void bone_row_sums(const double* directions, const double* radii, size_t n, size_t bone_count, size_t bone,
                   std::vector<double>& scratch, double* row) {
  double* units = scratch.data();
  double* squares = units + 3 * n;
  double* r = squares + n;
  for (size_t a = 0; a < n; ++a) {
    const double* d = directions + 3 * (a * bone_count + bone);
    std::copy(d, d + 3, units + 3 * a);
    squares[a] = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    r[a] = radii[a * bone_count + bone];
  }
  std::fill(row, row + n, 0.0);
  bool turns = false;
  for (size_t a = 1; a < n && !turns; ++a) turns = !std::equal(units, units + 3, units + 3 * a);
  if (!turns) return;  // one direction in every frame: theta = 0
  for (size_t a = 0; a < n; ++a) {
    double sum = 0.0;
    for (size_t b = a + 1; b < n; ++b) {
      const double arc = 0.5 * (r[a] + r[b]) * angle_between(units + 3 * a, units + 3 * b, squares[a], squares[b]);
      sum += arc;
      row[b] += arc;
    }
    row[a] += sum;
  }
}

}  // namespace

Status posture_error_row_sums(const double* directions, const double* radii, size_t frame_count, size_t bone_count,
                              unsigned threads, double* out) {
  for (size_t t = 0; t < frame_count; ++t)
    for (size_t c = 0; c < bone_count; ++c) {
      const double* d = directions + 3 * (t * bone_count + c);
      if (!std::isfinite(d[0]) || !std::isfinite(d[1]) || !std::isfinite(d[2]) ||
          !std::isfinite(radii[t * bone_count + c]))
        return Status::error("posture error: frame " + std::to_string(t) + ", bone " + std::to_string(c) +
                             " has a non-finite direction or length");
    }
  std::atomic<size_t> next{0};
  auto worker = [&]() {
    std::vector<double> scratch(5 * frame_count);
    for (size_t bone = next++; bone < bone_count; bone = next++)
      bone_row_sums(directions, radii, frame_count, bone_count, bone, scratch, out + bone * frame_count);
  };
  detail::run_workers(threads, bone_count, worker);
  return Status::success();
}

}  // namespace animlod
