#include <doctest/doctest.h>

#include <vector>

#include "animlod/tdag_time_tag.hpp"

using animlod::FrameRange;
using animlod::TaggedSet;
using animlod::TimeTag;

namespace {

std::vector<FrameRange> ranges(std::initializer_list<FrameRange> list) { return list; }

}  // namespace

TEST_CASE("time tag: alive at the frames of its half-open ranges") {
  TimeTag tag(2, 5);
  tag.add({8, 10});
  CHECK_FALSE(tag.alive_at(1));
  CHECK(tag.alive_at(2));
  CHECK(tag.alive_at(4));
  CHECK_FALSE(tag.alive_at(5));  // death is not alive
  CHECK_FALSE(tag.alive_at(7));
  CHECK(tag.alive_at(9));
  CHECK_FALSE(tag.alive_at(10));
  CHECK(tag.frame_count() == 5);
  CHECK(TimeTag(3, 3).empty());
}

TEST_CASE("time tag: adding merges overlapping and touching ranges, in any order") {
  TimeTag tag;
  tag.add({10, 12});
  tag.add({0, 2});
  tag.add({4, 6});
  CHECK(tag.ranges() == ranges({{0, 2}, {4, 6}, {10, 12}}));
  tag.add({2, 4});  // touches both neighbours: one range
  CHECK(tag.ranges() == ranges({{0, 6}, {10, 12}}));
  tag.add({5, 11});
  CHECK(tag.ranges() == ranges({{0, 12}}));
  // Frames added one by one in order make one range (the online construction's pattern).
  TimeTag frames;
  for (int32_t t = 3; t < 9; ++t) frames.add(t);
  CHECK(frames.ranges() == ranges({{3, 9}}));
  frames.add(10);
  CHECK(frames.ranges() == ranges({{3, 9}, {10, 11}}));
}

TEST_CASE("time tag: removing splits a range, union, intersection and difference") {
  TimeTag tag(0, 10);
  tag.remove({3, 5});
  CHECK(tag.ranges() == ranges({{0, 3}, {5, 10}}));
  tag.remove({0, 1});
  tag.remove({9, 20});
  CHECK(tag.ranges() == ranges({{1, 3}, {5, 9}}));
  tag.remove({1, 9});
  CHECK(tag.empty());

  TimeTag a(0, 4), b(2, 8);
  a.add({10, 12});
  CHECK(a.united(b).ranges() == ranges({{0, 8}, {10, 12}}));
  CHECK(a.intersected(b).ranges() == ranges({{2, 4}}));
  CHECK(a.minus(b).ranges() == ranges({{0, 2}, {10, 12}}));
  CHECK(b.minus(a).ranges() == ranges({{4, 8}}));
  // The canonical form makes equality a comparison of frames.
  TimeTag c(0, 2), d(0, 1);
  d.add(1);
  CHECK(c == d);
}

TEST_CASE("tagged set: several values alive at once, each on its own frames") {
  TaggedSet<int> links;
  for (int32_t t = 0; t < 4; ++t) links.add(10, t);
  links.add(11, 2);
  links.add(11, TimeTag(5, 7));
  std::vector<int> at2, at5;
  links.for_each_at(2, [&](int v) { at2.push_back(v); });
  links.for_each_at(5, [&](int v) { at5.push_back(v); });
  CHECK(at2 == std::vector<int>{10, 11});
  CHECK(at5 == std::vector<int>{11});
  CHECK(links.entries().size() == 2);
}
