// Time tags of the TDAG (Shamir and Pascucci, "Temporal and spatial level of details for
// dynamic meshes", Section 2): a value of a field is alive on one or more half-open frame
// ranges [birth, death). The TDAG tags each collapse with the frames whose hierarchy uses it;
// a multiple-valued field (the dependency links) holds several values, each with its own tag.
// Its error bounds, which on a capture change nearly every frame, are held as one value per
// collapse and frame instead.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace animlod {

// Frames [birth, death), birth < death.
struct FrameRange {
  int32_t birth = 0;
  int32_t death = 0;

  bool contains(int32_t frame) const { return birth <= frame && frame < death; }
  bool operator==(const FrameRange& other) const { return birth == other.birth && death == other.death; }
};

// A set of frames stored as sorted, disjoint, non-adjacent half-open ranges (the canonical
// form: two tags hold the same frames exactly when their ranges are equal).
class TimeTag {
 public:
  TimeTag() = default;
  // The frames [birth, death); empty when death <= birth.
  TimeTag(int32_t birth, int32_t death) { add({birth, death}); }

  // True when `frame` is in the tag. O(log R) for R ranges.
  bool alive_at(int32_t frame) const;
  // Adds the frames of `range` (no-op when empty), merging ranges that overlap or touch.
  void add(FrameRange range);
  // Adds one frame; O(1) when it extends the last range (frames added in increasing order).
  void add(int32_t frame) { add(FrameRange{frame, frame + 1}); }
  // Removes the frames of `range`, splitting a range that contains it.
  void remove(FrameRange range);
  // Frames in this tag or in `other`.
  TimeTag united(const TimeTag& other) const;
  // Frames in this tag and in `other`.
  TimeTag intersected(const TimeTag& other) const;
  // Frames in this tag but not in `other`.
  TimeTag minus(const TimeTag& other) const;

  bool empty() const { return ranges_.empty(); }
  // Number of frames in the tag.
  int64_t frame_count() const;
  const std::vector<FrameRange>& ranges() const { return ranges_; }
  bool operator==(const TimeTag& other) const { return ranges_ == other.ranges_; }
  bool operator!=(const TimeTag& other) const { return !(*this == other); }

 private:
  std::vector<FrameRange> ranges_;  // sorted by birth; ranges_[i].death < ranges_[i + 1].birth
};

// A multiple-valued field over time: several values, each alive on its own tag (e.g. the
// parents of a vertex node, or the collapses a node depends on).
template <typename T>
class TaggedSet {
 public:
  struct Entry {
    T value;
    TimeTag tag;
  };

  // Makes `value` alive at `frame` too (adds the value when new).
  void add(const T& value, int32_t frame) { entry(value).tag.add(frame); }
  void add(const T& value, const TimeTag& tag) {
    Entry& e = entry(value);
    e.tag = e.tag.united(tag);
  }
  // Calls visit(value) for every value alive at `frame`, in insertion order.
  template <typename Visit>
  void for_each_at(int32_t frame, Visit&& visit) const {
    for (const Entry& e : entries_)
      if (e.tag.alive_at(frame)) visit(e.value);
  }
  const std::vector<Entry>& entries() const { return entries_; }

 private:
  Entry& entry(const T& value) {
    for (Entry& e : entries_)
      if (e.value == value) return e;
    entries_.push_back({value, TimeTag{}});
    return entries_.back();
  }

  std::vector<Entry> entries_;
};

}  // namespace animlod
