#include <doctest/doctest.h>

#include <cmath>
#include <string>
#include <vector>

#include "animlod/ffd_lattice.hpp"

namespace {
using animlod::LatticeBox;
using animlod::LatticeSetView;
using animlod::LatticeView;

// Control points of the regular lattice of `box` (the identity deformation), l x m x n.
std::vector<double> regular_lattice(const LatticeBox& box, size_t l, size_t m, size_t n) {
  std::vector<double> points;
  for (size_t i = 0; i < l; ++i)
    for (size_t j = 0; j < m; ++j)
      for (size_t k = 0; k < n; ++k) {
        const double s = double(i) / double(l - 1), t = double(j) / double(m - 1), u = double(k) / double(n - 1);
        for (int d = 0; d < 3; ++d)
          points.push_back(box.origin[d] + s * box.axes[0][d] + t * box.axes[1][d] + u * box.axes[2][d]);
      }
  return points;
}

// A few points spread through the unit cube (and two outside it).
std::vector<float> sample_local() {
  std::vector<float> local;
  for (int p = 0; p < 20; ++p) {
    local.push_back(float(std::fmod(0.37 * p + 0.05, 1.0)));
    local.push_back(float(std::fmod(0.61 * p + 0.11, 1.0)));
    local.push_back(float(std::fmod(0.23 * p + 0.17, 1.0)));
  }
  return local;
}

double bernstein(int degree, int i, double x) {
  double binomial = 1.0;
  for (int q = 1; q <= i; ++q) binomial = binomial * (degree - i + q) / q;
  return binomial * std::pow(x, i) * std::pow(1.0 - x, degree - i);
}
}  // namespace

TEST_CASE("ffd_local_coordinates inverts an oblique box") {
  LatticeBox box;
  box.origin[0] = 1.0;
  box.origin[1] = -2.0;
  box.origin[2] = 0.5;
  const double axes[3][3] = {{2.0, 0.0, 0.0}, {0.5, 1.0, 0.0}, {0.0, 0.3, 0.7}};
  for (int a = 0; a < 3; ++a)
    for (int d = 0; d < 3; ++d) box.axes[a][d] = axes[a][d];
  const double s = 0.25, t = 0.5, u = 0.75;
  std::vector<float> point(3);
  for (int d = 0; d < 3; ++d) point[d] = float(box.origin[d] + s * axes[0][d] + t * axes[1][d] + u * axes[2][d]);
  std::vector<float> local(3);
  REQUIRE(animlod::ffd_local_coordinates(box, point.data(), 1, local.data()).ok);
  CHECK(local[0] == doctest::Approx(s));
  CHECK(local[1] == doctest::Approx(t));
  CHECK(local[2] == doctest::Approx(u));
}

TEST_CASE("ffd_local_coordinates names a box degenerate in one axis") {
  LatticeBox box;
  box.axes[2][0] = 1.0;  // U = (1, 0, 1): fine
  box.axes[2][2] = 1.0;
  std::vector<float> point = {0.1f, 0.2f, 0.3f}, local(3);
  CHECK(animlod::ffd_local_coordinates(box, point.data(), 1, local.data()).ok);
  box.axes[2][2] = 0.0;  // U = (1, 0, 0) lies in the plane of S and T
  const animlod::Status flat = animlod::ffd_local_coordinates(box, point.data(), 1, local.data());
  REQUIRE_FALSE(flat.ok);
  CHECK(flat.message.find("lie in one plane") != std::string::npos);
  box.axes[2][0] = 0.0;  // U = 0: a box without extent along U
  const animlod::Status zero = animlod::ffd_local_coordinates(box, point.data(), 1, local.data());
  REQUIRE_FALSE(zero.ok);
  CHECK(zero.message.find("axis U is degenerate") != std::string::npos);
}

TEST_CASE("a regular lattice is the identity, for 3x3x3, 2x2x2 and 4x2x3 lattices") {
  LatticeBox box;
  box.origin[0] = -1.0;
  box.axes[0][0] = 2.0;
  box.axes[1][1] = 3.0;
  box.axes[2][2] = 0.5;
  const std::vector<float> local = sample_local();
  const size_t count = local.size() / 3;
  for (const auto& size : std::vector<std::vector<size_t>>{{3, 3, 3}, {2, 2, 2}, {4, 2, 3}}) {
    const std::vector<double> controls = regular_lattice(box, size[0], size[1], size[2]);
    LatticeView lattice;
    for (int a = 0; a < 3; ++a) lattice.size[a] = size[a];
    lattice.control_points = controls.data();
    std::vector<float> out(local.size());
    REQUIRE(animlod::ffd_evaluate(lattice, local.data(), count, out.data()).ok);
    for (size_t p = 0; p < count; ++p) {
      CHECK(out[3 * p] == doctest::Approx(-1.0 + 2.0 * local[3 * p]).epsilon(1e-5));
      CHECK(out[3 * p + 1] == doctest::Approx(3.0 * local[3 * p + 1]).epsilon(1e-5));
      CHECK(out[3 * p + 2] == doctest::Approx(0.5 * local[3 * p + 2]).epsilon(1e-5));
    }
  }
}

TEST_CASE("the rational FFD with unit weights equals the Bezier sum, and weights pull towards their point") {
  // A random-ish 3x3x3 lattice, evaluated by the explicit Bernstein formula.
  std::vector<double> controls(27 * 3);
  for (size_t c = 0; c < controls.size(); ++c) controls[c] = std::sin(1.3 * double(c) + 0.2);
  const std::vector<float> local = sample_local();
  const size_t count = local.size() / 3;
  LatticeView lattice;
  lattice.control_points = controls.data();
  std::vector<float> plain(local.size());
  REQUIRE(animlod::ffd_evaluate(lattice, local.data(), count, plain.data()).ok);
  std::vector<double> ones(27, 1.0);
  lattice.weights = ones.data();
  std::vector<float> weighted(local.size());
  REQUIRE(animlod::ffd_evaluate(lattice, local.data(), count, weighted.data()).ok);
  for (size_t p = 0; p < count; ++p) {
    double expected[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) {
          const double b = bernstein(2, i, local[3 * p]) * bernstein(2, j, local[3 * p + 1]) *
                           bernstein(2, k, local[3 * p + 2]);
          for (int d = 0; d < 3; ++d) expected[d] += b * controls[3 * ((i * 3 + j) * 3 + k) + d];
        }
    for (int d = 0; d < 3; ++d) {
      CHECK(plain[3 * p + d] == doctest::Approx(expected[d]).epsilon(1e-5));
      CHECK(weighted[3 * p + d] == plain[3 * p + d]);
    }
  }
  // A heavier centre control point pulls the cube's centre towards it.
  const std::vector<float> centre = {0.5f, 0.5f, 0.5f};
  std::vector<float> light(3), heavy(3);
  ones[13] = 1.0;
  REQUIRE(animlod::ffd_evaluate(lattice, centre.data(), 1, light.data()).ok);
  ones[13] = 50.0;
  REQUIRE(animlod::ffd_evaluate(lattice, centre.data(), 1, heavy.data()).ok);
  double before = 0, after = 0;
  for (int d = 0; d < 3; ++d) {
    before += std::pow(light[d] - controls[3 * 13 + d], 2);
    after += std::pow(heavy[d] - controls[3 * 13 + d], 2);
  }
  CHECK(after < 0.1 * before);
}

TEST_CASE("ffd_evaluate rejects a bad size or weight, naming it") {
  std::vector<double> controls(27 * 3, 0.0), weights(27, 1.0);
  std::vector<float> local = {0.5f, 0.5f, 0.5f}, out(3);
  LatticeView lattice;
  lattice.control_points = controls.data();
  lattice.size[1] = 1;
  CHECK(animlod::ffd_evaluate(lattice, local.data(), 1, out.data()).message.find("axis T") != std::string::npos);
  lattice.size[1] = 3;
  weights[7] = 0.0;
  lattice.weights = weights.data();
  CHECK(animlod::ffd_evaluate(lattice, local.data(), 1, out.data()).message.find("control point 7") !=
        std::string::npos);
}

TEST_CASE("ffd_displace: zero displacement leaves every vertex, -1 vertices stay, frames are independent") {
  const std::vector<float> rest = {0.1f, 0.2f, 0.3f, 1.0f, 1.0f, 1.0f, 0.7f, 0.4f, 0.9f};
  const std::vector<float> local = {0.1f, 0.2f, 0.3f, 0.5f, 0.5f, 0.5f, 0.7f, 0.4f, 0.9f};
  const std::vector<int32_t> vertex_lattice = {0, -1, 1};
  const std::vector<int32_t> sizes = {3, 3, 3, 2, 2, 2};
  // Frame 0: nothing moves; frame 1: every control point of lattice 1 moves by (0, 0, 2), those
  // of lattice 0 by (1, 0, 0), with rational weights that must not matter for a uniform shift.
  std::vector<double> displacements(2 * 35 * 3, 0.0);
  for (size_t c = 0; c < 27; ++c) displacements[3 * (35 + c)] = 1.0;
  for (size_t c = 27; c < 35; ++c) displacements[3 * (35 + c) + 2] = 2.0;
  std::vector<double> weights(35);
  for (size_t c = 0; c < 35; ++c) weights[c] = 0.5 + 0.1 * double(c % 7);
  LatticeSetView set;
  set.lattice_count = 2;
  set.sizes = sizes.data();
  set.displacements = displacements.data();
  set.weights = weights.data();
  set.frame_count = 2;
  std::vector<float> out(2 * 9);
  REQUIRE(animlod::ffd_displace(set, rest.data(), local.data(), vertex_lattice.data(), 3, out.data()).ok);
  for (size_t q = 0; q < 9; ++q) CHECK(out[q] == rest[q]);
  CHECK(out[9 + 0] == doctest::Approx(rest[0] + 1.0));
  CHECK(out[9 + 1] == doctest::Approx(rest[1]));
  CHECK(out[9 + 3] == rest[3]);
  CHECK(out[9 + 6] == doctest::Approx(rest[6]));
  CHECK(out[9 + 8] == doctest::Approx(rest[8] + 2.0));

  const std::vector<int32_t> bad = {0, 2, 1};
  const animlod::Status status = animlod::ffd_displace(set, rest.data(), local.data(), bad.data(), 3, out.data());
  REQUIRE_FALSE(status.ok);
  CHECK(status.message.find("vertex 1") != std::string::npos);
}

TEST_CASE("ffd_displace with unit weights equals the FFD of the displaced regular lattice") {
  LatticeBox box;
  box.axes[0][0] = 2.0;
  const std::vector<double> regular = regular_lattice(box, 3, 3, 3);
  std::vector<double> delta(27 * 3), moved(27 * 3);
  for (size_t c = 0; c < delta.size(); ++c) {
    delta[c] = 0.1 * std::cos(0.7 * double(c));
    moved[c] = regular[c] + delta[c];
  }
  const std::vector<float> local = sample_local();
  const size_t count = local.size() / 3;
  std::vector<float> rest(local.size());
  for (size_t p = 0; p < count; ++p) {
    rest[3 * p] = 2.0f * local[3 * p];
    rest[3 * p + 1] = local[3 * p + 1];
    rest[3 * p + 2] = local[3 * p + 2];
  }
  LatticeView lattice;
  lattice.control_points = moved.data();
  std::vector<float> expected(local.size()), out(local.size());
  REQUIRE(animlod::ffd_evaluate(lattice, local.data(), count, expected.data()).ok);
  const std::vector<int32_t> sizes = {3, 3, 3}, vertex_lattice(count, 0);
  LatticeSetView set;
  set.lattice_count = 1;
  set.sizes = sizes.data();
  set.displacements = delta.data();
  REQUIRE(animlod::ffd_displace(set, rest.data(), local.data(), vertex_lattice.data(), count, out.data()).ok);
  for (size_t q = 0; q < out.size(); ++q) CHECK(out[q] == doctest::Approx(expected[q]).epsilon(1e-5));
}

TEST_CASE("a 2x2x2 lattice fitted to a trilinear field reproduces it, a 3x3x3 fit reproduces a quadratic one") {
  const std::vector<float> local = sample_local();
  const size_t count = local.size() / 3;
  // Trilinear field: corner vectors blended by s, t, u.
  std::vector<float> targets(local.size());
  for (size_t p = 0; p < count; ++p) {
    const double s = local[3 * p], t = local[3 * p + 1], u = local[3 * p + 2];
    targets[3 * p] = float(0.3 + 0.2 * s * t - 0.1 * u + 0.4 * s * t * u);
    targets[3 * p + 1] = float(-0.2 * t + 0.05 * s * u);
    targets[3 * p + 2] = float(0.1 * s + 0.3 * t * u);
  }
  const size_t two[3] = {2, 2, 2};
  std::vector<double> fitted(8 * 3);
  animlod::FfdFitOptions exact;
  exact.smoothness = exact.ridge = 0.0;
  REQUIRE(animlod::ffd_fit(two, nullptr, local.data(), targets.data(), count, nullptr, fitted.data(), exact).ok);
  LatticeView lattice;
  lattice.size[0] = lattice.size[1] = lattice.size[2] = 2;
  lattice.control_points = fitted.data();
  std::vector<float> back(local.size());
  REQUIRE(animlod::ffd_evaluate(lattice, local.data(), count, back.data()).ok);
  for (size_t q = 0; q < back.size(); ++q) CHECK(back[q] == doctest::Approx(targets[q]).epsilon(1e-5));
  // With the default regularisation and the exact lattice as the prior, the fit stays exact.
  const std::vector<double> prior = fitted;
  REQUIRE(animlod::ffd_fit(two, nullptr, local.data(), targets.data(), count, prior.data(), fitted.data()).ok);
  for (size_t q = 0; q < fitted.size(); ++q) CHECK(fitted[q] == doctest::Approx(prior[q]).epsilon(1e-6));

  // A quadratic field is not trilinear: the 2x2x2 fit leaves a residual, the 3x3x3 fit none.
  for (size_t p = 0; p < count; ++p) targets[3 * p] = float(local[3 * p] * local[3 * p]);
  REQUIRE(animlod::ffd_fit(two, nullptr, local.data(), targets.data(), count, nullptr, fitted.data()).ok);
  REQUIRE(animlod::ffd_evaluate(lattice, local.data(), count, back.data()).ok);
  double residual = 0.0;
  for (size_t p = 0; p < count; ++p) residual = std::max(residual, std::abs(double(back[3 * p]) - targets[3 * p]));
  CHECK(residual > 1e-2);
  const size_t three[3] = {3, 3, 3};
  std::vector<double> fitted3(27 * 3);
  REQUIRE(animlod::ffd_fit(three, nullptr, local.data(), targets.data(), count, nullptr, fitted3.data(), exact).ok);
  LatticeView lattice3;
  lattice3.control_points = fitted3.data();
  REQUIRE(animlod::ffd_evaluate(lattice3, local.data(), count, back.data()).ok);
  for (size_t q = 0; q < back.size(); ++q) CHECK(back[q] == doctest::Approx(targets[q]).epsilon(1e-4));
}

TEST_CASE("ffd_fit regularisation keeps a thin region's lattice tame and still fits it") {
  // 30 points in a slab 1e-4 thick: plain least squares is free to use huge control points
  // that cancel at the points; the regularised fit is small and fits almost as well.
  std::vector<float> local, targets;
  for (int p = 0; p < 30; ++p) {
    const float s = float(std::fmod(0.37 * p + 0.05, 1.0)), t = float(std::fmod(0.61 * p + 0.11, 1.0));
    local.insert(local.end(), {s, t, 0.5f + 1e-4f * float(p % 3)});
    // A smooth field plus 1e-3 of noise: plain least squares explains the noise with the slab's
    // 1e-4 thickness, which takes control points of order 1e-3 / 1e-4 times the basis.
    targets.insert(targets.end(), {0.0f, float(s * s + 0.3 * t * s), float(1e-3 * ((7 * p) % 5 - 2))});
  }
  const size_t three[3] = {3, 3, 3};
  std::vector<double> tame(81), wild(81);
  animlod::FfdFitOptions plain;
  plain.smoothness = plain.ridge = 0.0;
  REQUIRE(animlod::ffd_fit(three, nullptr, local.data(), targets.data(), 30, nullptr, wild.data(), plain).ok);
  REQUIRE(animlod::ffd_fit(three, nullptr, local.data(), targets.data(), 30, nullptr, tame.data()).ok);
  double largest_tame = 0.0, largest_wild = 0.0;
  for (size_t q = 0; q < 81; ++q) {
    largest_tame = std::max(largest_tame, std::abs(tame[q]));
    largest_wild = std::max(largest_wild, std::abs(wild[q]));
  }
  CHECK(largest_tame < 2.0);
  CHECK(largest_wild > 10.0 * largest_tame);
  LatticeView lattice;
  lattice.control_points = tame.data();
  std::vector<float> back(local.size());
  REQUIRE(animlod::ffd_evaluate(lattice, local.data(), 30, back.data()).ok);
  for (size_t q = 0; q < back.size(); ++q) CHECK(back[q] == doctest::Approx(targets[q]).epsilon(0.02).scale(1.0));
  animlod::FfdFitOptions negative;
  negative.ridge = -1.0;
  CHECK_FALSE(animlod::ffd_fit(three, nullptr, local.data(), targets.data(), 30, nullptr, tame.data(), negative).ok);
}

TEST_CASE("ffd_fit with points in a plane returns the least-norm solution, and rejects no points") {
  std::vector<float> local, targets;
  for (int p = 0; p < 12; ++p) {
    local.insert(local.end(), {float(p % 4) / 3.0f, float(p / 4) / 2.0f, 0.5f});
    targets.insert(targets.end(), {0.0f, 1.0f, 0.0f});
  }
  const size_t two[3] = {2, 2, 2};
  std::vector<double> fitted(24);
  animlod::FfdFitOptions exact;
  exact.smoothness = exact.ridge = 0.0;
  REQUIRE(animlod::ffd_fit(two, nullptr, local.data(), targets.data(), 12, nullptr, fitted.data(), exact).ok);
  for (size_t c = 0; c < 8; ++c) CHECK(fitted[3 * c + 1] == doctest::Approx(1.0));  // least norm: equal halves
  CHECK_FALSE(animlod::ffd_fit(two, nullptr, local.data(), targets.data(), 0, nullptr, fitted.data()).ok);
  // With the default ridge the free direction (P at u = 0 minus P at u = 1) keeps the prior's 3,
  // and the determined one (their mean, 1) is fitted: 2.5 and -0.5.
  std::vector<double> prior(24, 0.0);
  for (size_t c = 0; c < 8; c += 2) prior[3 * c + 1] = 3.0;
  REQUIRE(animlod::ffd_fit(two, nullptr, local.data(), targets.data(), 12, prior.data(), fitted.data()).ok);
  for (size_t c = 0; c < 8; ++c) CHECK(fitted[3 * c + 1] == doctest::Approx(c % 2 == 0 ? 2.5 : -0.5).epsilon(1e-3));
}
