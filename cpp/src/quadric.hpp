// One frame's quadric error of Eqs. 1-3: Q(v) = v^T A v - 2 b^T v + c with A = sum n n^T,
// b = sum (n^T p0) n, c = sum (n^T p0)^2 over planes n^T x = n^T p0. The 3F-dimensional
// quadric of Eq. 4 is block-diagonal, so AQEM stores F of these per vertex, contiguously.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

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

  // Eq. 5: the minimiser v = A^-1 b. Returns false when A is (nearly) singular, i.e. its
  // determinant is tiny against the cube of its scale (flat or ridge-like neighbourhoods).
  bool minimizer(Eigen::Vector3d& v) const {
    Eigen::Matrix3d a;
    a << a00, a01, a02, a01, a11, a12, a02, a12, a22;
    const double scale = a00 + a11 + a22;
    if (!(scale > 0.0)) return false;
    Eigen::Matrix3d inverse;
    double determinant = 0.0;
    bool invertible = false;
    a.computeInverseAndDetWithCheck(inverse, determinant, invertible, 1e-9 * scale * scale * scale);
    if (!invertible) return false;
    v = inverse * Eigen::Vector3d(b0, b1, b2);
    return v.allFinite();
  }
};

}  // namespace animlod::detail
