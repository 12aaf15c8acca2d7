// One frame's quadric error of Eqs. 1-3: Q(v) = v^T A v - 2 b^T v + c with A = sum n n^T,
// b = sum (n^T p0) n, c = sum (n^T p0)^2 over planes n^T x = n^T p0. The 3F-dimensional
// quadric of Eq. 4 is block-diagonal, so AQEM stores F of these per vertex, contiguously.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace animlod::detail {

struct Quadric {
  // Upper triangle of the symmetric A, then b, then c: ten doubles, no padding.
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0;
  double b0 = 0, b1 = 0, b2 = 0;
  double c = 0;

  // The plane through `point` with unit normal `normal`, scaled by `weight`.
  static Quadric plane(const Eigen::Vector3d& normal, const Eigen::Vector3d& point, double weight) {
    const double d = normal.dot(point);
    const Eigen::Vector3d n = normal;
    return {weight * n.x() * n.x(), weight * n.x() * n.y(), weight * n.x() * n.z(),
            weight * n.y() * n.y(), weight * n.y() * n.z(), weight * n.z() * n.z(),
            weight * d * n.x(),     weight * d * n.y(),     weight * d * n.z(),
            weight * d * d};
  }

  // weight |v - point|^2: the squared distance from a point.
  static Quadric point(const Eigen::Vector3d& point, double weight) {
    return {weight, 0, 0, weight, 0, weight, weight * point.x(), weight * point.y(), weight * point.z(),
            weight * point.squaredNorm()};
  }

  Quadric& operator+=(const Quadric& q) {
    a00 += q.a00; a01 += q.a01; a02 += q.a02; a11 += q.a11; a12 += q.a12; a22 += q.a22;
    b0 += q.b0; b1 += q.b1; b2 += q.b2;
    c += q.c;
    return *this;
  }
  friend Quadric operator+(Quadric a, const Quadric& b) { return a += b; }

  // Q(v), clamped at 0 against rounding (a sum of squares is never negative).
  double evaluate(const Eigen::Vector3d& v) const {
    const double x = v.x(), y = v.y(), z = v.z();
    const double quadratic = a00 * x * x + a11 * y * y + a22 * z * z + 2.0 * (a01 * x * y + a02 * x * z + a12 * y * z);
    const double value = quadratic - 2.0 * (b0 * x + b1 * y + b2 * z) + c;
    return value > 0.0 ? value : 0.0;
  }

  // Along the line p + t d: Q = Q(p) + 2 t slope + t^2 curvature. Adds curvature = d^T A d and
  // slope = (A p - b) . d to the running sums (for one t shared by all frames).
  void accumulate_line(const Eigen::Vector3d& p, const Eigen::Vector3d& d, double& curvature, double& slope) const {
    const Eigen::Vector3d ad(a00 * d.x() + a01 * d.y() + a02 * d.z(), a01 * d.x() + a11 * d.y() + a12 * d.z(),
                             a02 * d.x() + a12 * d.y() + a22 * d.z());
    curvature += ad.dot(d);
    slope += ad.dot(p) - (b0 * d.x() + b1 * d.y() + b2 * d.z());
  }

};

// Eq. 5 for the merged quadrics kept[k] + removed[k] of K frames at once: the minimiser
// v = A^-1 b of each and Q(v) there. A frame is unsolved when A is (nearly) singular, i.e. its
// determinant is tiny against the cube of its scale (flat or ridge-like neighbourhoods), or v
// is not finite. The frames sit in arrays (one per coefficient) and the loop has no branch, so
// the compiler works on several frames per instruction: every edge cost runs it, K frames deep.
class MergedMinimizers {
 public:
  void solve(const Quadric* kept, const Quadric* removed, size_t frame_count) {
    frame_count_ = frame_count;
    if (columns_.size() < kColumns * frame_count) columns_.resize(kColumns * frame_count);
    double* merged = columns_.data();
    if (frame_count == 1) {  // nothing to vectorise over: the columns' set-up cost more than the solve
      const Quadric q = kept[0] + removed[0];
      minimum(q.a00, q.a01, q.a02, q.a11, q.a12, q.a22, q.b0, q.b1, q.b2, q.c, merged[kX], merged[kY], merged[kZ],
              merged[kValue], merged[kSolved]);
      return;
    }
    for (size_t k = 0; k < frame_count; ++k) {
      const Quadric q = kept[k] + removed[k];
      const double coefficients[10] = {q.a00, q.a01, q.a02, q.a11, q.a12, q.a22, q.b0, q.b1, q.b2, q.c};
      for (size_t i = 0; i < 10; ++i) merged[i * frame_count + k] = coefficients[i];
    }
    minimise(frame_count, merged, merged + kX * frame_count, merged + kSolved * frame_count);
  }

  bool solved(size_t k) const { return column(kSolved)[k] != 0.0; }
  // Frame k counts as unsolved after all (its minimiser is out of reach: AqemPolicy).
  void reject(size_t k) { columns_[kSolved * frame_count_ + k] = 0.0; }
  Eigen::Vector3d position(size_t k) const { return {column(kX)[k], column(kY)[k], column(kZ)[k]}; }
  double value(size_t k) const { return column(kValue)[k]; }

 private:
  // Columns of K: the merged quadrics' ten coefficients, then the results.
  enum : size_t { kX = 10, kY, kZ, kValue, kSolved, kColumns };
  const double* column(size_t i) const { return columns_.data() + i * frame_count_; }

  // n frames: ten columns of coefficients in; x, y, z and Q out, and 1 or 0 into `solved`
  // (GCC 12 vectorised the loop with two output pointers, not with one).
  static void minimise(size_t n, const double* __restrict in, double* __restrict out, double* __restrict solved) {
    for (size_t k = 0; k < n; ++k)
      minimum(in[k], in[n + k], in[2 * n + k], in[3 * n + k], in[4 * n + k], in[5 * n + k], in[6 * n + k],
              in[7 * n + k], in[8 * n + k], in[9 * n + k], out[k], out[n + k], out[2 * n + k], out[3 * n + k], solved[k]);
  }

  // One merged quadric's minimiser (x, y, z), Q there, and 1 or 0 into `solved`. Inlined into
  // minimise's loop, which GCC vectorises only with the whole body in view.
  [[gnu::always_inline]] static inline void minimum(double a00, double a01, double a02, double a11, double a12,
                                                    double a22, double b0, double b1, double b2, double c, double& out_x,
                                                    double& out_y, double& out_z, double& value, double& solved) {
    // The adjugate over the determinant. The products and sums are those of Eigen's 3x3
    // inverse and product, which this replaced, in the same order: levels stay bit for bit.
    const double c0 = a11 * a22 - a12 * a12, c1 = a12 * a02 - a22 * a01, c2 = a01 * a12 - a02 * a11;
    const double determinant = (c0 * a00 + c1 * a01) + c2 * a02;
    const double inverse = 1.0 / determinant;
    const double x = (c0 * inverse * b0 + c1 * inverse * b1) + c2 * inverse * b2;
    const double y = ((a12 * a02 - a01 * a22) * inverse * b0 + (a22 * a00 - a02 * a02) * inverse * b1) +
                     (a02 * a01 - a00 * a12) * inverse * b2;
    const double z = (a01 * a12 - a11 * a02) * inverse * b0 +
                     ((a02 * a01 - a12 * a00) * inverse * b1 + (a00 * a11 - a01 * a01) * inverse * b2);
    out_x = x, out_y = y, out_z = z;
    value = Quadric{a00, a01, a02, a11, a12, a22, b0, b1, b2, c}.evaluate(Eigen::Vector3d(x, y, z));
    // Selects, not && (a branch would stop the vectorisation); x - x is NaN for inf and NaN.
    const double scale = a00 + a11 + a22;
    double regular = scale > 0.0 ? 1.0 : 0.0;
    regular = std::abs(determinant) > 1e-9 * scale * scale * scale ? regular : 0.0;
    solved = (x - x) + (y - y) + (z - z) == 0.0 ? regular : 0.0;
  }

  size_t frame_count_ = 0;
  std::vector<double> columns_;  // (kColumns, K)
};

}  // namespace animlod::detail
