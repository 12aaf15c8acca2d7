#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "../../cpp/src/cost_order.hpp"

namespace {

struct Costed {
  double cost;
};

// The comparison sort's order by (cost, index), which CostOrder must give.
std::vector<uint32_t> reference_order(const std::vector<Costed>& items) {
  std::vector<uint32_t> order(items.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return items[a].cost < items[b].cost; });
  return order;
}

std::vector<uint32_t> read_order(animlod::detail::CostOrder& order, size_t count) {
  std::vector<uint32_t> indices;
  for (size_t k = 0; k < count; ++k) indices.push_back(order[k]);
  return indices;
}

}  // namespace

TEST_CASE("cost order is the comparison sort's by (cost, index), ties in the top bits included") {
  std::mt19937 random(11);
  std::vector<Costed> items;
  for (int i = 0; i < 300000; ++i) {  // above the two workers' threshold
    const double base = std::ldexp(1.0 + double(random() % 64) / 64.0, int(random() % 40) - 30);
    switch (random() % 7) {
      case 0: items.push_back({base}); break;  // exact ties among the 64 x 40 values
      case 1: items.push_back({std::nextafter(base, 1.0)}); break;  // differs below the radix bits only
      case 2: items.push_back({-base * double(random() % 1000) * 1e-3}); break;  // negative (rounding)
      case 3: items.push_back({(random() % 2) != 0 ? 0.0 : -0.0}); break;  // -0 ties with +0
      case 4: items.push_back({1.0 + double(random() % 100000) * 1e-9}); break;  // one large top-bits bucket
      case 5: items.push_back({std::nextafter(1.0 + double(random() % 100) * 1e-9, 2.0)}); break;  // ... tied below its radix bits
      default: items.push_back({double(random()) * 1e-9}); break;
    }
  }
  items.push_back({std::numeric_limits<double>::infinity()});
  items.push_back({-std::numeric_limits<double>::infinity()});
  std::shuffle(items.begin(), items.end(), random);
  animlod::detail::CostOrder order;
  order.sort(items);
  CHECK(read_order(order, items.size()) == reference_order(items));
  // Read only in part (the rest is never ordered), then again from the start.
  order.sort(items);
  const std::vector<uint32_t> prefix = read_order(order, items.size() / 3);
  CHECK(std::equal(prefix.begin(), prefix.end(), reference_order(items).begin()));
  CHECK(read_order(order, items.size()) == reference_order(items));
  // Buffers reused: a smaller, all-equal input (every radix pass skipped) keeps index order.
  items.assign(1000, Costed{0.5});
  order.sort(items);
  CHECK(read_order(order, items.size()) == reference_order(items));
  items.clear();
  order.sort(items);
  CHECK(order.size() == 0);
}
