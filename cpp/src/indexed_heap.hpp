// A binary min-heap over ids [0, N) with a position index, so that a key can be raised,
// lowered or removed in O(log N) (AQEM steps 7-11: edges around a new vertex are re-keyed in
// place, no stale entries pile up). Keys live inside the heap array, so sifting compares
// neighbouring memory instead of chasing ids. Ties are broken by the smaller id, for
// determinism.
#pragma once

#include <cstdint>
#include <vector>

namespace animlod::detail {

class IndexedMinHeap {
 public:
  explicit IndexedMinHeap(size_t id_count) : position_(id_count, -1) {}

  bool empty() const { return heap_.empty(); }
  size_t size() const { return heap_.size(); }
  bool contains(int32_t id) const { return position_[id] >= 0; }
  int32_t top() const { return heap_.front().id; }

  // Replaces the contents with `ids` and their `keys` in O(N) (Floyd's heap construction).
  void assign(const std::vector<int32_t>& ids, const std::vector<double>& keys) {
    for (const Entry& entry : heap_) position_[entry.id] = -1;
    heap_.resize(ids.size());
    for (size_t i = 0; i < ids.size(); ++i) {
      heap_[i] = {keys[i], ids[i]};
      position_[ids[i]] = static_cast<int32_t>(i);
    }
    for (auto slot = static_cast<int32_t>(heap_.size() / 2) - 1; slot >= 0; --slot) sift_down(slot);
  }

  // Inserts `id` or changes its key.
  void set(int32_t id, double key) {
    if (!contains(id)) {
      position_[id] = static_cast<int32_t>(heap_.size());
      heap_.push_back({key, id});
      sift_up(position_[id]);
      return;
    }
    const int32_t slot = position_[id];
    const double old_key = heap_[slot].key;
    heap_[slot].key = key;
    if (key < old_key) sift_up(slot);
    else sift_down(slot);
  }

  void remove(int32_t id) {
    if (!contains(id)) return;
    const int32_t hole = position_[id];
    const Entry last = heap_.back();
    heap_.pop_back();
    position_[id] = -1;
    if (last.id == id) return;
    place(hole, last);
    sift_up(hole);
    sift_down(position_[last.id]);
  }

 private:
  struct Entry {
    double key;
    int32_t id;
  };

  static bool less(const Entry& a, const Entry& b) { return a.key < b.key || (a.key == b.key && a.id < b.id); }

  void place(int32_t slot, const Entry& entry) {
    heap_[slot] = entry;
    position_[entry.id] = slot;
  }

  void sift_up(int32_t slot) {
    const Entry entry = heap_[slot];
    while (slot > 0) {
      const int32_t parent = (slot - 1) / 2;
      if (!less(entry, heap_[parent])) break;
      place(slot, heap_[parent]);
      slot = parent;
    }
    place(slot, entry);
  }

  void sift_down(int32_t slot) {
    const Entry entry = heap_[slot];
    const auto count = static_cast<int32_t>(heap_.size());
    while (true) {
      int32_t child = 2 * slot + 1;
      if (child >= count) break;
      if (child + 1 < count && less(heap_[child + 1], heap_[child])) ++child;
      if (!less(heap_[child], entry)) break;
      place(slot, heap_[child]);
      slot = child;
    }
    place(slot, entry);
  }

  std::vector<int32_t> position_;  // slot in heap_, -1 when absent
  std::vector<Entry> heap_;
};

}  // namespace animlod::detail
