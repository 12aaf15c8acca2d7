// Disjoint sets with path halving, for fans around vertices and motion-feature components.
#pragma once

#include <cstdint>
#include <numeric>
#include <vector>

namespace animlod::detail {

class UnionFind {
 public:
  explicit UnionFind(size_t count) : parent_(count) { std::iota(parent_.begin(), parent_.end(), 0); }

  int32_t find(int32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }

  // The smaller root becomes the parent, so roots are deterministic.
  void unite(int32_t a, int32_t b) {
    a = find(a);
    b = find(b);
    if (a < b) parent_[b] = a;
    else if (b < a) parent_[a] = b;
  }

 private:
  std::vector<int32_t> parent_;
};

}  // namespace animlod::detail
