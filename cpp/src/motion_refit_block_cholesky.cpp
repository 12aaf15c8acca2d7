// Sparse block Cholesky of a free-point cluster's Hessian (see the header). Phases: at
// construction the elimination order (minimum degree on the coupling graph, ties by node index:
// deterministic) and the fill it makes; per factorisation the right-looking block elimination
// L_kk = chol(A_kk), L_jk = A_jk L_kk^-T, A_ij -= L_ik L_jk^T over the pattern worked out once.
#include "motion_refit_block_cholesky.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <set>

namespace animlod::detail {

namespace {

using Block = BlockCholesky::Block;

// Lower Cholesky factor of a symmetric 3 x 3 block (its lower triangle is read); false when
// it is not positive definite or not finite.
bool cholesky3(const Block& a, Block& l) {
  l = {};
  const double d0 = a[0];
  if (!(d0 > 0.0) || !std::isfinite(d0)) return false;
  l[0] = std::sqrt(d0);
  l[3] = a[3] / l[0];
  l[6] = a[6] / l[0];
  const double d1 = a[4] - l[3] * l[3];
  if (!(d1 > 0.0) || !std::isfinite(d1)) return false;
  l[4] = std::sqrt(d1);
  l[7] = (a[7] - l[6] * l[3]) / l[4];
  const double d2 = a[8] - l[6] * l[6] - l[7] * l[7];
  if (!(d2 > 0.0) || !std::isfinite(d2)) return false;
  l[8] = std::sqrt(d2);
  return true;
}

// Solves L y = b in place (L lower 3 x 3).
void forward3(const Block& l, double* b) {
  b[0] /= l[0];
  b[1] = (b[1] - l[3] * b[0]) / l[4];
  b[2] = (b[2] - l[6] * b[0] - l[7] * b[1]) / l[8];
}

// Solves L^T x = y in place.
void backward3(const Block& l, double* y) {
  y[2] /= l[8];
  y[1] = (y[1] - l[7] * y[2]) / l[4];
  y[0] = (y[0] - l[3] * y[1] - l[6] * y[2]) / l[0];
}

}  // namespace

BlockCholesky::BlockCholesky(size_t nodes, const std::vector<std::pair<int32_t, int32_t>>& coupled) {
  // Minimum-degree elimination on the coupling graph, with fill.
  std::vector<std::set<int32_t>> neighbours(nodes);
  for (const auto& [a, b] : coupled) {
    assert(a != b && a >= 0 && b >= 0 && static_cast<size_t>(a) < nodes && static_cast<size_t>(b) < nodes);
    neighbours[a].insert(b);
    neighbours[b].insert(a);
  }
  std::vector<uint8_t> done(nodes, 0);
  std::vector<std::vector<int32_t>> later(nodes);  // a node's neighbours when it is eliminated
  for (size_t step = 0; step < nodes; ++step) {
    int32_t best = -1;
    for (size_t v = 0; v < nodes; ++v)
      if (!done[v] && (best < 0 || neighbours[v].size() < neighbours[best].size())) best = static_cast<int32_t>(v);
    order_.push_back(best);
    done[best] = 1;
    later[best].assign(neighbours[best].begin(), neighbours[best].end());
    for (int32_t a : later[best]) {
      neighbours[a].erase(best);
      for (int32_t b : later[best])
        if (a != b) neighbours[a].insert(b);
    }
  }
  position_.assign(nodes, 0);
  for (size_t k = 0; k < nodes; ++k) position_[order_[k]] = static_cast<int32_t>(k);
  below_start_.assign(nodes + 1, 0);
  for (size_t k = 0; k < nodes; ++k) {
    std::vector<int32_t> rows;
    for (int32_t v : later[order_[k]]) rows.push_back(position_[v]);
    std::sort(rows.begin(), rows.end());
    below_.insert(below_.end(), rows.begin(), rows.end());
    below_start_[k + 1] = static_cast<int32_t>(below_.size());
  }
  // The updates of each elimination step: every pair (i >= j) of its later neighbours.
  update_start_.assign(nodes + 1, 0);
  for (size_t k = 0; k < nodes; ++k) {
    for (int32_t e = below_start_[k]; e < below_start_[k + 1]; ++e)
      for (int32_t f = below_start_[k]; f <= e; ++f) {
        const int32_t i = below_[e], j = below_[f];
        updates_.push_back({e, f, i == j ? -1 - i : slot(i, j)});
      }
    update_start_[k + 1] = static_cast<int32_t>(updates_.size());
  }
  diagonal_.assign(nodes, Block{});
  offdiagonal_.assign(below_.size(), Block{});
}

int32_t BlockCholesky::slot(int32_t position_row, int32_t position_column) const {
  for (int32_t e = below_start_[position_column]; e < below_start_[position_column + 1]; ++e)
    if (below_[e] == position_row) return e;
  assert(false && "block outside the pattern");
  return -1;
}

void BlockCholesky::clear() {
  std::fill(diagonal_.begin(), diagonal_.end(), Block{});
  std::fill(offdiagonal_.begin(), offdiagonal_.end(), Block{});
}

void BlockCholesky::add(int32_t a, int32_t b, const double* block) {
  const int32_t pa = position_[a], pb = position_[b];
  if (pa == pb) {
    for (int i = 0; i < 9; ++i) diagonal_[pa][i] += block[i];
    return;
  }
  if (pa > pb) {  // (a, b) is below the diagonal: as given
    Block& target = offdiagonal_[slot(pa, pb)];
    for (int i = 0; i < 9; ++i) target[i] += block[i];
  } else {  // stored as (b, a): the transpose
    Block& target = offdiagonal_[slot(pb, pa)];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) target[3 * r + c] += block[3 * c + r];
  }
}

bool BlockCholesky::factor(double shift) {
  factor_diagonal_ = diagonal_;
  factor_offdiagonal_ = offdiagonal_;
  for (Block& d : factor_diagonal_)
    for (int i = 0; i < 3; ++i) d[4 * i] += shift;
  const size_t n = order_.size();
  for (size_t k = 0; k < n; ++k) {
    Block l;
    if (!cholesky3(factor_diagonal_[k], l)) return false;
    factor_diagonal_[k] = l;
    for (int32_t e = below_start_[k]; e < below_start_[k + 1]; ++e) {  // L_jk = A_jk L_kk^-T
      Block& a = factor_offdiagonal_[e];
      for (int r = 0; r < 3; ++r) forward3(l, &a[3 * r]);  // row r of A_jk times L_kk^-T
    }
    for (int32_t u = update_start_[k]; u < update_start_[k + 1]; ++u) {  // A_ij -= L_ik L_jk^T
      const Update& update = updates_[u];
      const Block& li = factor_offdiagonal_[update.first];
      const Block& lj = factor_offdiagonal_[update.second];
      Block& target = update.target >= 0 ? factor_offdiagonal_[update.target] : factor_diagonal_[-1 - update.target];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          target[3 * r + c] -= li[3 * r] * lj[3 * c] + li[3 * r + 1] * lj[3 * c + 1] + li[3 * r + 2] * lj[3 * c + 2];
    }
  }
  return true;
}

bool BlockCholesky::factor_least_shift(double base, int& rung) {
  const auto shift = [base](int k) { return std::ldexp(base, 2 * k); };  // base 4^k, exactly
  bool factored = false;  // whether the last factorisation succeeded
  while (rung > 0 && (factored = factor(shift(rung - 1)))) --rung;
  while (!factored) {
    if (!std::isfinite(shift(rung))) return false;
    if (!(factored = factor(shift(rung)))) ++rung;
  }
  return true;
}

void BlockCholesky::solve(const double* rhs, double* x) {
  const size_t n = order_.size();
  std::vector<double>& y = work_;
  y.resize(3 * n);
  for (size_t k = 0; k < n; ++k) std::copy_n(rhs + 3 * order_[k], 3, y.begin() + 3 * static_cast<long>(k));
  for (size_t k = 0; k < n; ++k) {  // L y = b
    double* yk = &y[3 * k];
    forward3(factor_diagonal_[k], yk);
    for (int32_t e = below_start_[k]; e < below_start_[k + 1]; ++e) {
      const Block& l = factor_offdiagonal_[e];
      double* yj = &y[3 * static_cast<size_t>(below_[e])];
      for (int r = 0; r < 3; ++r) yj[r] -= l[3 * r] * yk[0] + l[3 * r + 1] * yk[1] + l[3 * r + 2] * yk[2];
    }
  }
  for (size_t k = n; k-- > 0;) {  // L^T x = y
    double* yk = &y[3 * k];
    for (int32_t e = below_start_[k]; e < below_start_[k + 1]; ++e) {
      const Block& l = factor_offdiagonal_[e];
      const double* xj = &y[3 * static_cast<size_t>(below_[e])];
      for (int c = 0; c < 3; ++c) yk[c] -= l[c] * xj[0] + l[3 + c] * xj[1] + l[6 + c] * xj[2];
    }
    backward3(factor_diagonal_[k], yk);
  }
  for (size_t k = 0; k < n; ++k) std::copy_n(y.begin() + 3 * static_cast<long>(k), 3, x + 3 * order_[k]);
}

std::vector<double> BlockCholesky::dense() const {
  const size_t n = order_.size(), m = 3 * n;
  std::vector<double> matrix(m * m, 0.0);
  auto put = [&](int32_t a, int32_t b, const Block& block) {  // node rows a, columns b
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) matrix[(3 * a + r) * m + 3 * b + c] = block[3 * r + c];
  };
  for (size_t k = 0; k < n; ++k) {
    put(order_[k], order_[k], diagonal_[k]);
    for (int32_t e = below_start_[k]; e < below_start_[k + 1]; ++e) {
      const Block& b = offdiagonal_[e];
      put(order_[below_[e]], order_[k], b);
      put(order_[k], order_[below_[e]], {b[0], b[3], b[6], b[1], b[4], b[7], b[2], b[5], b[8]});
    }
  }
  return matrix;
}

}  // namespace animlod::detail
