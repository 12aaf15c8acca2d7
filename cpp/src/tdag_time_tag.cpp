// Time-tag algebra of the TDAG (Shamir and Pascucci 2001, Section 2): sets of frames as sorted,
// disjoint, non-adjacent half-open ranges [birth, death).
#include "animlod/tdag_time_tag.hpp"

namespace animlod {

bool TimeTag::alive_at(int32_t frame) const {
  // The last range starting at or before `frame`.
  auto after = std::upper_bound(ranges_.begin(), ranges_.end(), frame,
                                [](int32_t f, const FrameRange& range) { return f < range.birth; });
  return after != ranges_.begin() && (after - 1)->contains(frame);
}

void TimeTag::add(FrameRange range) {
  if (range.death <= range.birth) return;
  // Fast path: frames added in increasing order extend or follow the last range.
  if (ranges_.empty() || range.birth > ranges_.back().death) {
    ranges_.push_back(range);
    return;
  }
  if (range.birth >= ranges_.back().birth) {
    ranges_.back().death = std::max(ranges_.back().death, range.death);
    return;
  }
  // General case: merge every range that overlaps or touches [birth, death).
  std::vector<FrameRange> merged;
  merged.reserve(ranges_.size() + 1);
  size_t i = 0;
  while (i < ranges_.size() && ranges_[i].death < range.birth) merged.push_back(ranges_[i++]);
  FrameRange joined = range;
  while (i < ranges_.size() && ranges_[i].birth <= range.death) {
    joined.birth = std::min(joined.birth, ranges_[i].birth);
    joined.death = std::max(joined.death, ranges_[i].death);
    ++i;
  }
  merged.push_back(joined);
  while (i < ranges_.size()) merged.push_back(ranges_[i++]);
  ranges_ = std::move(merged);
}

void TimeTag::remove(FrameRange range) {
  if (range.death <= range.birth) return;
  std::vector<FrameRange> kept;
  kept.reserve(ranges_.size() + 1);
  for (const FrameRange& r : ranges_) {
    if (r.death <= range.birth || r.birth >= range.death) {
      kept.push_back(r);
      continue;
    }
    if (r.birth < range.birth) kept.push_back({r.birth, range.birth});
    if (range.death < r.death) kept.push_back({range.death, r.death});
  }
  ranges_ = std::move(kept);
}

TimeTag TimeTag::united(const TimeTag& other) const {
  TimeTag out = *this;
  for (const FrameRange& r : other.ranges_) out.add(r);
  return out;
}

TimeTag TimeTag::intersected(const TimeTag& other) const {
  TimeTag out;
  size_t i = 0, j = 0;
  while (i < ranges_.size() && j < other.ranges_.size()) {
    const FrameRange& a = ranges_[i];
    const FrameRange& b = other.ranges_[j];
    const int32_t birth = std::max(a.birth, b.birth), death = std::min(a.death, b.death);
    if (birth < death) out.ranges_.push_back({birth, death});  // sorted, disjoint: no merge needed
    (a.death < b.death ? i : j)++;
  }
  return out;
}

TimeTag TimeTag::minus(const TimeTag& other) const {
  TimeTag out = *this;
  for (const FrameRange& r : other.ranges_) out.remove(r);
  return out;
}

int64_t TimeTag::frame_count() const {
  int64_t count = 0;
  for (const FrameRange& r : ranges_) count += r.death - r.birth;
  return count;
}

}  // namespace animlod
