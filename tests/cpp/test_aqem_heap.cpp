#include <doctest/doctest.h>

#include <map>
#include <random>

#include "../../cpp/src/indexed_heap.hpp"
#include "../../cpp/src/skin_merge.hpp"

using animlod::detail::IndexedMinHeap;

TEST_CASE("indexed heap agrees with an ordered map under random inserts, updates and removals") {
  std::mt19937 random(7);
  IndexedMinHeap heap(50);
  std::map<int32_t, double> reference;
  for (int step = 0; step < 2000; ++step) {
    const int32_t id = int32_t(random() % 50);
    const double key = double(random() % 20);  // many ties
    if (random() % 3 == 0) {
      heap.remove(id);
      reference.erase(id);
    } else {
      heap.set(id, key);
      reference[id] = key;
    }
    REQUIRE(heap.size() == reference.size());
    if (reference.empty()) continue;
    auto best = reference.begin();
    for (auto it = reference.begin(); it != reference.end(); ++it)
      if (it->second < best->second) best = it;  // first minimum: smallest id among ties
    CHECK(heap.top() == best->first);
  }
}

TEST_CASE("skin weights merge to the top K, sorted and normalised") {
  int32_t joints[2] = {1, 2};
  float weights[2] = {0.6f, 0.4f};
  const int32_t other_joints[2] = {3, 1};
  const float other_weights[2] = {0.9f, 0.1f};
  animlod::detail::merge_skin_weights(joints, weights, other_joints, other_weights, 2, 0.5);
  // Blend: joint 1 -> 0.3 + 0.05, joint 2 -> 0.2, joint 3 -> 0.45; keep 3 and 1.
  CHECK(joints[0] == 3);
  CHECK(joints[1] == 1);
  CHECK(weights[0] == doctest::Approx(0.45 / 0.8));
  CHECK(weights[1] == doctest::Approx(0.35 / 0.8));
}
