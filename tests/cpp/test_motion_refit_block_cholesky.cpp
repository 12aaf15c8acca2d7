// The sparse block Cholesky of free-point clusters (cpp/src/motion_refit_block_cholesky.hpp):
// on the coupling pattern of angle triples along a skeleton (a point with its parent and
// grandparent) and on a pattern that needs fill, its solve matches Eigen's dense LLT; it
// refuses an indefinite matrix and factorises it once shifted, as the Newton step needs, with
// the least shift of a ladder found from any starting rung.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "../../cpp/src/motion_refit_block_cholesky.hpp"

using animlod::detail::BlockCholesky;
using Pairs = std::vector<std::pair<int32_t, int32_t>>;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

namespace {

// Fills matrix with random blocks on the pattern (symmetric), diagonal + dominance on the
// diagonal blocks (0: possibly indefinite).
void fill_random(BlockCholesky& matrix, const Pairs& pairs, double dominance, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  matrix.clear();
  for (const auto& [a, b] : pairs) {
    double block[9];
    for (double& v : block) v = value(rng);
    matrix.add(a, b, block);
  }
  for (size_t k = 0; k < matrix.nodes(); ++k) {
    double block[9];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c <= r; ++c) block[3 * r + c] = block[3 * c + r] = value(rng) + (r == c ? dominance : 0.0);
    matrix.add(static_cast<int32_t>(k), static_cast<int32_t>(k), block);
  }
}

// max |x - dense solve| / max |dense solve| for (A + shift I) x = b.
double solve_error(BlockCholesky& matrix, double shift, unsigned seed) {
  const auto n = static_cast<Eigen::Index>(3 * matrix.nodes());
  const std::vector<double> dense = matrix.dense();
  RowMatrix a = Eigen::Map<const RowMatrix>(dense.data(), n, n);
  a += shift * RowMatrix::Identity(n, n);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  Eigen::VectorXd rhs(n);
  for (Eigen::Index i = 0; i < n; ++i) rhs[i] = value(rng);
  const Eigen::LLT<Eigen::MatrixXd> llt(a);
  REQUIRE(llt.info() == Eigen::Success);
  const Eigen::VectorXd expected = llt.solve(rhs);
  std::vector<double> x(static_cast<size_t>(n));
  matrix.solve(rhs.data(), x.data());
  double error = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) error = std::max(error, std::abs(x[i] - expected[i]));
  return error / expected.cwiseAbs().maxCoeff();
}

// A skeleton's angle-triple pattern: parents (-1: root) and every (parent, joint, child) triple.
Pairs skeleton_pattern(const std::vector<int32_t>& parent) {
  Pairs pairs;
  for (size_t c = 0; c < parent.size(); ++c) {
    const int32_t j = parent[c];
    if (j < 0) continue;
    pairs.emplace_back(static_cast<int32_t>(c), j);
    if (parent[j] >= 0) pairs.emplace_back(static_cast<int32_t>(c), parent[j]);
  }
  return pairs;
}

}  // namespace

TEST_CASE("block Cholesky: a hand's pattern (parents and grandparents) solves as the dense LLT") {
  // A wrist (0) with five fingers of three joints and an end site each, numbered out of order.
  std::vector<int32_t> parent(21, -1);
  int32_t next = 1;
  for (int finger = 0; finger < 5; ++finger) {
    int32_t above = 0;
    for (int segment = 0; segment < 4; ++segment, ++next) {
      parent[next] = above;
      above = next;
    }
  }
  // Node k of the matrix is point shuffled[k] (5 and 21 are coprime: a permutation).
  std::vector<int32_t> shuffled(parent.size());
  for (size_t k = 0; k < parent.size(); ++k) shuffled[k] = static_cast<int32_t>((5 * k + 3) % parent.size());
  std::vector<int32_t> node_of(parent.size());
  for (size_t k = 0; k < parent.size(); ++k) node_of[shuffled[k]] = static_cast<int32_t>(k);
  Pairs pairs;
  for (const auto& [a, b] : skeleton_pattern(parent)) pairs.emplace_back(node_of[a], node_of[b]);
  BlockCholesky matrix(parent.size(), pairs);
  fill_random(matrix, pairs, 20.0, 1);
  REQUIRE(matrix.factor(0.0));
  CHECK(solve_error(matrix, 0.0, 2) < 1e-12);
  // Adding a block twice (both orders) adds the transpose: the dense matrix stays symmetric.
  const std::vector<double> dense = matrix.dense();
  const size_t n = 3 * parent.size();
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < i; ++j) CHECK(dense[i * n + j] == dense[j * n + i]);
}

TEST_CASE("block Cholesky: a pattern that needs fill (a cycle) solves as the dense LLT") {
  const Pairs pairs = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 0}, {2, 5}, {5, 1}};
  BlockCholesky matrix(6, pairs);
  fill_random(matrix, pairs, 15.0, 3);
  REQUIRE(matrix.factor(0.0));
  CHECK(solve_error(matrix, 0.0, 4) < 1e-12);
  // The same pairs given in the other order make the same matrix.
  Pairs swapped;
  for (const auto& [a, b] : pairs) swapped.emplace_back(b, a);
  BlockCholesky other(6, swapped);
  fill_random(other, pairs, 15.0, 3);
  CHECK(other.dense() == matrix.dense());
}

TEST_CASE("block Cholesky: an indefinite matrix is refused, and factorised once shifted") {
  std::vector<int32_t> parent = {-1, 0, 1, 2, 1, 4};
  const Pairs pairs = skeleton_pattern(parent);
  BlockCholesky matrix(parent.size(), pairs);
  fill_random(matrix, pairs, -3.0, 5);
  CHECK_FALSE(matrix.factor(0.0));
  REQUIRE(matrix.factor(40.0));
  CHECK(solve_error(matrix, 40.0, 6) < 1e-12);
  // The matrix survives a failed factorisation: the shifted one still matches.
  CHECK_FALSE(matrix.factor(0.0));
  REQUIRE(matrix.factor(40.0));
  CHECK(solve_error(matrix, 40.0, 7) < 1e-12);
}

TEST_CASE("block Cholesky: the least shift is found from any rung, as counting up from 0 finds it") {
  std::vector<int32_t> parent = {-1, 0, 1, 2, 1, 4};
  const Pairs pairs = skeleton_pattern(parent);
  BlockCholesky matrix(parent.size(), pairs);
  fill_random(matrix, pairs, -3.0, 5);
  const double base = 0.01;
  int counted = 0;  // the first k whose shift base 4^k factorises, counting up
  while (!matrix.factor(std::ldexp(base, 2 * counted))) ++counted;
  REQUIRE(counted > 2);
  for (int start : {0, counted - 1, counted, counted + 1, counted + 7}) {
    int rung = start;
    REQUIRE(matrix.factor_least_shift(base, rung));
    CHECK(rung == counted);
    CHECK(solve_error(matrix, std::ldexp(base, 2 * counted), 8) < 1e-12);  // the factors are the shifted matrix's
  }
  int rung = 0;
  matrix.clear();  // a matrix with no finite positive definite shift: NaN on the diagonal
  const double nan_block[9] = {std::nan(""), 0, 0, 0, 1, 0, 0, 0, 1};
  matrix.add(0, 0, nan_block);
  CHECK_FALSE(matrix.factor_least_shift(base, rung));
}
