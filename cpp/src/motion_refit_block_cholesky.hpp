// Sparse Cholesky factorisation over 3 x 3 blocks, for the Hessian of a cluster of free points
// in the motion re-fit (motion_refit_free_points.hpp; seeds/000, Eqs. 6 and 8).
//
// A cluster's Hessian couples two points only when one angle triple (parent, frozen joint,
// child) holds both: a point with its parent, its grandparent, its children and grandchildren
// in the skeleton. Eliminated in a minimum-degree order (leaves of the skeleton first), each
// point then has at most its parent and grandparent left as neighbours, so the factorisation
// creates no fill beyond those pairs and costs O(points) per Newton step instead of the dense
// factorisation's O(points^3): on the coarsest levels of a skeleton with fingers a cluster holds
// the ~30 points of both arms and hands (90 unknowns). The order and the fill are worked out
// once, from the coupling pattern; every factorisation then reuses them.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace animlod::detail {

class BlockCholesky {
 public:
  using Block = std::array<double, 9>;  // 3 x 3, row-major

  BlockCholesky() = default;
  // nodes: points (3 unknowns each); coupled: pairs of nodes (in [0, nodes), a != b) whose
  // block may be non-zero. Repeats are allowed.
  BlockCholesky(size_t nodes, const std::vector<std::pair<int32_t, int32_t>>& coupled);

  size_t nodes() const { return order_.size(); }

  // Sets the matrix to zero (the pattern stays).
  void clear();
  // Adds block (3 x 3 row-major) to the (a, b) block of the symmetric matrix; a == b is a
  // diagonal block. For a != b only one of (a, b) and (b, a) needs adding: the other is its
  // transpose. (a, b) must be coupled (or a == b).
  void add(int32_t a, int32_t b, const double* block);
  // Factorises the matrix plus shift * I (L L^T, in the elimination order); false when it is
  // not positive definite (or not finite). The matrix added so far is kept, so a failed call
  // can be repeated with a larger shift.
  bool factor(double shift);
  // Factorises the matrix plus the least shift base * 4^k (k >= 0) that makes it positive
  // definite; false if none is finite. rung: the k to search from, set to the k found. Positive
  // definiteness only grows with the shift, so stepping down or up from the last k finds the same
  // k as counting up from 0, in two factorisations where k repeats (counting up takes k + 1).
  bool factor_least_shift(double base, int& rung);
  // Solves (matrix + shift) x = rhs with the last successful factorisation; rhs and x are
  // (nodes, 3) in node order and may be the same array.
  void solve(const double* rhs, double* x);

  // The assembled matrix (without shift) as a dense (3 nodes)^2 row-major array (for tests).
  std::vector<double> dense() const;

 private:
  // Blocks are stored per elimination position k: the diagonal block of the node eliminated
  // k-th, and one block per later neighbour j (row j, column k of the lower triangle).
  int32_t slot(int32_t position_row, int32_t position_column) const;

  std::vector<int32_t> order_;     // (nodes,) node eliminated at each position
  std::vector<int32_t> position_;  // (nodes,) inverse of order_
  // Per position k: later neighbours' positions (increasing) in below_[below_start_[k] ..
  // below_start_[k + 1]); their blocks in offdiagonal_[same index].
  std::vector<int32_t> below_start_, below_;
  std::vector<Block> diagonal_, offdiagonal_;  // the assembled matrix
  std::vector<Block> factor_diagonal_, factor_offdiagonal_;  // L: lower Cholesky factors
  // Per update of the factorisation: where L_jk L_ik^T goes (target slot; -1 - position for a
  // diagonal block), computed once.
  struct Update {
    int32_t first, second;  // indices into below_ of the two factors (L_ik, L_jk), i >= j
    int32_t target;         // offdiagonal slot, or -1 - position for a diagonal block
  };
  std::vector<int32_t> update_start_;
  std::vector<Update> updates_;
  std::vector<double> work_;  // (nodes, 3) solve's right-hand side in elimination order
};

}  // namespace animlod::detail
