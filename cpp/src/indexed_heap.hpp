// A binary min-heap over ids [0, N) with a position index, so that a key can be raised,
// lowered or removed in O(log N) (AQEM steps 7-11: edges around a new vertex are re-keyed in
// place, no stale entries pile up). Ties are broken by the smaller id, for determinism.
#pragma once

#include <cassert>
#include <cstdint>
#include <vector>

namespace animlod::detail {

class IndexedMinHeap {
 public:
  explicit IndexedMinHeap(size_t id_count) : key_(id_count, 0.0), position_(id_count, -1) {}

  bool empty() const { return heap_.empty(); }
  size_t size() const { return heap_.size(); }
  bool contains(int32_t id) const { return position_[id] >= 0; }
  int32_t top() const { return heap_.front(); }
  double key(int32_t id) const { return key_[id]; }

  // Inserts `id` or changes its key.
  void set(int32_t id, double key) {
    if (!contains(id)) {
      key_[id] = key;
      position_[id] = static_cast<int32_t>(heap_.size());
      heap_.push_back(id);
      sift_up(position_[id]);
      return;
    }
    const double old_key = key_[id];
    key_[id] = key;
    if (key < old_key) sift_up(position_[id]);
    else sift_down(position_[id]);
  }

  void remove(int32_t id) {
    if (!contains(id)) return;
    const int32_t hole = position_[id];
    const int32_t last = heap_.back();
    heap_.pop_back();
    position_[id] = -1;
    if (last == id) return;
    heap_[hole] = last;
    position_[last] = hole;
    sift_up(hole);
    sift_down(position_[last]);
  }

 private:
  bool less(int32_t a, int32_t b) const { return key_[a] < key_[b] || (key_[a] == key_[b] && a < b); }

  void place(int32_t slot, int32_t id) {
    heap_[slot] = id;
    position_[id] = slot;
  }

  void sift_up(int32_t slot) {
    const int32_t id = heap_[slot];
    while (slot > 0) {
      const int32_t parent = (slot - 1) / 2;
      if (!less(id, heap_[parent])) break;
      place(slot, heap_[parent]);
      slot = parent;
    }
    place(slot, id);
  }

  void sift_down(int32_t slot) {
    const int32_t id = heap_[slot];
    const auto count = static_cast<int32_t>(heap_.size());
    while (true) {
      int32_t child = 2 * slot + 1;
      if (child >= count) break;
      if (child + 1 < count && less(heap_[child + 1], heap_[child])) ++child;
      if (!less(heap_[child], id)) break;
      place(slot, heap_[child]);
      slot = child;
    }
    place(slot, id);
  }

  std::vector<double> key_;
  std::vector<int32_t> position_;  // slot in heap_, -1 when absent
  std::vector<int32_t> heap_;
};

}  // namespace animlod::detail
