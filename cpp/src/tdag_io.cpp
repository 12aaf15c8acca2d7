// The .tdag file: the TDAG and its affine maps (Shamir and Pascucci 2001, Section 6 stores
// "the TDAG and affine maps"), versioned and checksummed.
//
// Layout (little-endian):
//   8 bytes   magic "ANLDTDAG"
//   u32       format version (kTdagFormatVersion)
//   u64       body length in bytes
//   body      the fields below
//   u32       CRC-32 (IEEE) of the body
// Body: unsigned LEB128 varints ("v"), zigzag varints for signed deltas ("z"), raw IEEE values:
//   v F, V, M, C; u8 affine base, u8 governing; z governing frame; f64 history weight, f64 scale
//   faces        z delta of each index from the one before (3 M values)
//   inputs       v input vertex count, u8 1 when input vertex v is TDAG vertex v, else each
//                input vertex's TDAG vertex as z delta from the one before (from -1)
//   two-sided    (version 2 on) v count, then each two-sided face as v (face - previous - 1),
//                the previous starting at -1
//   maps         F * 12 f64
//   residuals    frame 0: V * 3 f32; frame t > 0: a bit per vertex (changed since t - 1), then
//                the changed vertices' 3 f32 (a vertex that does not move is stored once)
//   per collapse: v (node - kept), v (node - removed), v killed[0] + 1, v killed[1] + 1,
//                tag (alive), v dependency count, per dependency z (node - dependency) and a tag
//                (v 0: the collapse's alive tag; else v range count + 1, then ranges), v error
//                run count, per run v ((length - 1) * 2 + gap?), [v gap from the previous
//                death], z code change
//   tag          v range count, per range v (birth - previous death), v length
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "animlod/tdag.hpp"
#include "crc32.hpp"
#include "tdag_data.hpp"

namespace animlod {

namespace {

constexpr char kMagic[8] = {'A', 'N', 'L', 'D', 'T', 'D', 'A', 'G'};
constexpr size_t kHeaderSize = 8 + 4 + 8;

// Calls run(begin, end) for each run of vertices whose bit is set in `changed` (one bit per
// vertex), in order, while it returns true: a frame's changed residuals are copied a run at a time.
template <typename Run>
void for_each_changed_run(const std::vector<uint8_t>& changed, size_t vertex_count, const Run& run) {
  auto is_changed = [&](size_t v) { return (changed[v / 8] & (1u << (v % 8))) != 0; };
  for (size_t v = 0; v < vertex_count; ++v) {
    if (!is_changed(v)) continue;
    size_t end = v + 1;
    while (end < vertex_count && is_changed(end)) ++end;
    if (!run(v, end)) return;
    v = end;  // unchanged (or the end)
  }
}

// Writes the file into `out`, whole; or, given a sink, into `out` as a buffer handed to the sink
// whenever it holds a chunk (a long clip's file is then never held whole).
class Writer {
 public:
  explicit Writer(std::vector<uint8_t>& out, TdagFileSink* sink = nullptr, size_t chunk = 0)
      : out_(out), sink_(sink), chunk_(std::max<size_t>(chunk, 1)) {}
  void u8(uint8_t v) {
    out_.push_back(v);
    flush_when_full();
  }
  template <typename T>
  void raw(T v) {
    uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    raw_array(bytes, sizeof(T));
  }
  template <typename T>
  void raw_array(const T* values, size_t count) {
    const auto* bytes = reinterpret_cast<const uint8_t*>(values);
    const size_t size = count * sizeof(T);
    if (sink_ != nullptr && size >= chunk_) {  // a long array goes to the sink as it is
      flush();
      pass(bytes, size);
      return;
    }
    out_.insert(out_.end(), bytes, bytes + size);
    flush_when_full();
  }
  void varint(uint64_t v) {
    while (v >= 0x80) {
      out_.push_back(static_cast<uint8_t>(v | 0x80));
      v >>= 7;
    }
    out_.push_back(static_cast<uint8_t>(v));
    flush_when_full();
  }
  void zigzag(int64_t v) { varint((static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63)); }
  void tag(const TimeTag& tag) {
    varint(tag.ranges().size());
    int32_t previous = 0;
    for (const FrameRange& r : tag.ranges()) {
      varint(static_cast<uint64_t>(r.birth - previous));
      varint(static_cast<uint64_t>(r.death - r.birth));
      previous = r.death;
    }
  }
  // The body's length into the header, then its checksum after it; false when the sink failed.
  bool finish() {
    if (sink_ == nullptr) {
      const uint64_t body_size = out_.size() - kHeaderSize;
      std::memcpy(out_.data() + kHeaderSize - sizeof(body_size), &body_size, sizeof(body_size));
      raw(detail::crc32(out_.data() + kHeaderSize, static_cast<size_t>(body_size)));
      return true;
    }
    flush();
    const uint64_t body_size = written_ - kHeaderSize;
    uint8_t length[sizeof(body_size)];
    std::memcpy(length, &body_size, sizeof(body_size));
    return ok_ && sink_->append(reinterpret_cast<const uint8_t*>(&crc_), sizeof(crc_)) &&
           sink_->overwrite(kHeaderSize - sizeof(body_size), length, sizeof(body_size));
  }

 private:
  void flush_when_full() {
    if (sink_ != nullptr && out_.size() >= chunk_) flush();
  }
  void flush() {
    pass(out_.data(), out_.size());
    out_.clear();
  }
  // To the sink, the body's part of it into the checksum.
  void pass(const uint8_t* bytes, size_t size) {
    if (size == 0 || !ok_) return;
    const size_t header = written_ < kHeaderSize ? std::min(size, kHeaderSize - static_cast<size_t>(written_)) : 0;
    crc_ = detail::crc32(bytes + header, size - header, crc_);
    written_ += size;
    ok_ = sink_->append(bytes, size);
  }

  std::vector<uint8_t>& out_;
  TdagFileSink* sink_;
  size_t chunk_;
  uint64_t written_ = 0;  // bytes handed to the sink
  uint32_t crc_ = 0;      // of the body's bytes among them
  bool ok_ = true;
};

// Reads the body; every read checks the end, and failures keep the first message. The bytes are
// all in memory, or come from a file a chunk at a time: a long clip's file need not be held
// beside the residuals it fills.
class Reader {
 public:
  Reader(const uint8_t* bytes, size_t size) : p_(bytes), end_(bytes + size) {}
  // `chunk`: the buffer, whose size is the largest read but for long arrays read in place.
  Reader(std::istream& file, uint64_t size, std::vector<uint8_t> chunk) : file_(&file), left_(size), chunk_(std::move(chunk)) {}
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  void fail(const std::string& why) {
    if (error_.empty()) error_ = why;
    p_ = end_;
    left_ = 0;
  }
  uint8_t u8(const char* what) {
    if (p_ == end_ && !refill(what)) return 0;
    return *p_++;
  }
  template <typename T>
  T raw(const char* what) {
    T v{};
    uint8_t bytes[sizeof(T)];
    if (take(bytes, sizeof(T), what)) std::memcpy(&v, bytes, sizeof(T));
    return v;
  }
  template <typename T>
  bool raw_array(T* out, size_t count, const char* what) {
    if (remaining() / sizeof(T) < count) {
      fail(std::string("truncated in ") + what);
      return false;
    }
    return take(reinterpret_cast<uint8_t*>(out), count * sizeof(T), what);
  }
  uint64_t varint(const char* what) {
    uint64_t v = 0;
    for (int shift = 0; shift < 64; shift += 7) {
      const uint8_t byte = u8(what);
      if (!ok()) return 0;
      v |= static_cast<uint64_t>(byte & 0x7F) << shift;
      if (!(byte & 0x80)) return v;
    }
    fail(std::string("malformed number in ") + what);
    return 0;
  }
  int64_t zigzag(const char* what) {
    const uint64_t v = varint(what);
    return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1);
  }
  // A count that must be at most `limit` (so that a corrupted count cannot allocate wildly).
  uint64_t count(const char* what, uint64_t limit) {
    const uint64_t v = varint(what);
    if (v > limit) fail(std::string(what) + ": " + std::to_string(v) + " exceeds " + std::to_string(limit));
    return ok() ? v : 0;
  }
  TimeTag tag(const char* what, int32_t frame_count) {
    TimeTag out;
    const uint64_t ranges = count(what, static_cast<uint64_t>(frame_count));
    int64_t previous = 0;
    for (uint64_t i = 0; i < ranges && ok(); ++i) {
      const int64_t birth = previous + static_cast<int64_t>(count(what, static_cast<uint64_t>(frame_count)));
      const int64_t death = birth + static_cast<int64_t>(count(what, static_cast<uint64_t>(frame_count)));
      if (birth < previous || death <= birth || death > frame_count) {
        fail(std::string(what) + ": range outside the frames");
        break;
      }
      out.add({static_cast<int32_t>(birth), static_cast<int32_t>(death)});
      previous = death;
    }
    return out;
  }
  size_t remaining() const { return static_cast<size_t>(end_ - p_) + static_cast<size_t>(left_); }

 private:
  // The next chunk of the file into the window; false (failed) at the end of the body.
  bool refill(const char* what) {
    const size_t size = static_cast<size_t>(std::min<uint64_t>(left_, chunk_.size()));
    if (size == 0 || !read_file(chunk_.data(), size)) {
      fail(std::string("truncated in ") + what);
      return false;
    }
    p_ = chunk_.data();
    end_ = p_ + size;
    return true;
  }
  bool read_file(uint8_t* out, size_t size) {
    file_->read(reinterpret_cast<char*>(out), static_cast<std::streamsize>(size));
    left_ -= size;
    return static_cast<size_t>(file_->gcount()) == size;
  }
  // `size` bytes into `out`: what the window holds, then a large rest straight from the file.
  bool take(uint8_t* out, size_t size, const char* what) {
    while (size > 0) {
      if (p_ == end_) {
        if (file_ != nullptr && size >= chunk_.size() && size <= left_) {
          if (read_file(out, size)) return true;
          fail(std::string("truncated in ") + what);
          return false;
        }
        if (!refill(what)) return false;
      }
      const size_t n = std::min(size, static_cast<size_t>(end_ - p_));
      std::memcpy(out, p_, n);
      p_ += n;
      out += n;
      size -= n;
    }
    return true;
  }

  const uint8_t* p_ = nullptr;
  const uint8_t* end_ = nullptr;
  std::istream* file_ = nullptr;  // null: every byte is in [p_, end_)
  uint64_t left_ = 0;             // the file's body bytes not yet read
  std::vector<uint8_t> chunk_;
  std::string error_;
};

// The order the cuts rely on (tdag_cut.cpp): a cut is a set of collapses closed under the
// dependencies of its frame, and it applies a collapse only with both children active, so a
// collapse child must be in the dependency closure of its parent at every frame the parent is
// alive. The builder links a collapse to the collapses that last changed the faces around its
// endpoints (tdag_hierarchy.cpp), which reach the children only through chains of such links,
// so the check is reachability, not a direct link. Per frame segment of one structure (the
// frames between two structure events), with a topological rank so that a search from a
// collapse only visits collapses ranked above the child it looks for. Also: no dependency
// cycle, children and linked collapses alive where the collapse (or link) is.
class DependencyOrderCheck {
 public:
  explicit DependencyOrderCheck(const detail::TdagData& d)
      : d_(d), collapse_count_(d.collapse_count()), rank_(collapse_count_), stamp_(collapse_count_, 0) {}

  Status run() {
    if (Status status = check_tags(); !status) return status;
    recheck_.assign(collapse_count_, 1);
    if (d_.static_structure) return check_frame(0);
    if (Status status = check_frame(0); !status) return status;
    // A later frame only changes the structure at its events. A path that held at the frame
    // before and broke crosses a link of an event collapse, which the start of the path still
    // reaches, so only the collapses that reach an event collapse (and those) are searched again.
    for (int32_t t = 1; t < d_.frame_count; ++t) {
      const auto begin = static_cast<size_t>(d_.event_offsets[static_cast<size_t>(t)]);
      const auto end = static_cast<size_t>(d_.event_offsets[static_cast<size_t>(t) + 1]);
      if (begin == end) continue;
      std::fill(recheck_.begin(), recheck_.end(), 0);
      stack_.clear();
      for (size_t i = begin; i < end; ++i) {
        const size_t c = collapse_of(d_.event_nodes[i]);
        if (!recheck_[c]) stack_.push_back(static_cast<int32_t>(c));
        recheck_[c] = 1;
      }
      while (!stack_.empty()) {
        const auto x = static_cast<size_t>(stack_.back());
        stack_.pop_back();
        for (int32_t k = d_.dependent_offsets[x]; k < d_.dependent_offsets[x + 1]; ++k) {
          if (!d_.link_alive(static_cast<size_t>(d_.dependent_links[static_cast<size_t>(k)]), t)) continue;
          const size_t m = collapse_of(d_.dependent_nodes[static_cast<size_t>(k)]);
          if (!recheck_[m]) stack_.push_back(static_cast<int32_t>(m));
          recheck_[m] = 1;
        }
      }
      if (Status status = check_frame(t); !status) return status;
    }
    return Status::success();
  }

 private:
  static std::string name(size_t c) { return "collapse " + std::to_string(c); }
  int32_t node(size_t c) const { return d_.vertex_count + static_cast<int32_t>(c); }
  bool is_collapse(int32_t n) const { return n >= d_.vertex_count; }
  size_t collapse_of(int32_t n) const { return static_cast<size_t>(n - d_.vertex_count); }

  // Children and dependencies alive wherever the collapse (or the link) is.
  Status check_tags() const {
    if (d_.static_structure) return Status::success();
    for (size_t c = 0; c < collapse_count_; ++c) {
      for (const int32_t child : {d_.kept_child[c], d_.removed_child[c]})
        if (is_collapse(child) && !d_.alive[c].minus(d_.alive[collapse_of(child)]).empty())
          return Status::error(name(c) + ": child node " + std::to_string(child) +
                               " is not in the hierarchy on every frame the collapse is");
      for (int32_t link = d_.dep_offsets[c]; link < d_.dep_offsets[c + 1]; ++link) {
        const TimeTag& tag = d_.dep_tags[static_cast<size_t>(link)];
        const int32_t dep = d_.dep_nodes[static_cast<size_t>(link)];
        if (!tag.minus(d_.alive[c]).empty() || !tag.minus(d_.alive[collapse_of(dep)]).empty())
          return Status::error(name(c) + ": dependency " + std::to_string(dep) +
                               " is linked on frames where it or the collapse is not in the hierarchy");
      }
    }
    return Status::success();
  }

  template <typename Visit>
  void for_each_dependency(size_t c, int32_t frame, Visit&& visit) const {
    for (int32_t link = d_.dep_offsets[c]; link < d_.dep_offsets[c + 1]; ++link)
      if (d_.link_alive(static_cast<size_t>(link), frame)) visit(collapse_of(d_.dep_nodes[static_cast<size_t>(link)]));
  }

  Status check_frame(int32_t frame) {
    const std::string at = d_.static_structure ? std::string() : " at frame " + std::to_string(frame);
    // Topological ranks (Kahn): a collapse ranks above every collapse it depends on.
    std::vector<int32_t> waiting(collapse_count_, 0), ready;
    for (size_t c = 0; c < collapse_count_; ++c) {
      if (!d_.collapse_alive(c, frame)) continue;
      for_each_dependency(c, frame, [&](size_t) { ++waiting[c]; });
      if (waiting[c] == 0) ready.push_back(static_cast<int32_t>(c));
    }
    std::fill(rank_.begin(), rank_.end(), -1);
    int32_t next = 0;
    for (size_t i = 0; i < ready.size(); ++i) {
      const auto c = static_cast<size_t>(ready[i]);
      rank_[c] = next++;
      for (int32_t k = d_.dependent_offsets[c]; k < d_.dependent_offsets[c + 1]; ++k) {
        if (!d_.link_alive(static_cast<size_t>(d_.dependent_links[static_cast<size_t>(k)]), frame)) continue;
        const size_t m = collapse_of(d_.dependent_nodes[static_cast<size_t>(k)]);
        if (d_.collapse_alive(m, frame) && --waiting[m] == 0) ready.push_back(static_cast<int32_t>(m));
      }
    }
    for (size_t c = 0; c < collapse_count_; ++c)
      if (d_.collapse_alive(c, frame) && rank_[c] < 0)
        return Status::error(name(c) + ": its dependencies form a cycle" + at);

    // Each collapse child within the dependency closure of its parent.
    for (size_t c = 0; c < collapse_count_; ++c) {
      if (!recheck_[c] || !d_.collapse_alive(c, frame)) continue;
      const std::array<int32_t, 2> children = {d_.kept_child[c], d_.removed_child[c]};
      std::array<bool, 2> found = {!is_collapse(children[0]), !is_collapse(children[1])};
      if (found[0] && found[1]) continue;
      int32_t lowest = std::numeric_limits<int32_t>::max();
      for (size_t i = 0; i < 2; ++i)
        if (!found[i]) lowest = std::min(lowest, rank_[collapse_of(children[i])]);
      ++generation_;
      stack_.assign(1, static_cast<int32_t>(c));
      while (!stack_.empty() && !(found[0] && found[1])) {
        const auto x = static_cast<size_t>(stack_.back());
        stack_.pop_back();
        for_each_dependency(x, frame, [&](size_t k) {
          for (size_t i = 0; i < 2; ++i) found[i] = found[i] || node(k) == children[i];
          if (rank_[k] > lowest && stamp_[k] != generation_) {
            stamp_[k] = generation_;
            stack_.push_back(static_cast<int32_t>(k));
          }
        });
      }
      for (size_t i = 0; i < 2; ++i)
        if (!found[i])
          return Status::error(name(c) + ": its " + (i == 0 ? "kept" : "removed") + " child, node " +
                               std::to_string(children[i]) + ", is not among the collapses it depends on" + at +
                               " (a cut could apply the collapse before its child)");
    }
    return Status::success();
  }

  const detail::TdagData& d_;
  size_t collapse_count_;
  std::vector<int32_t> rank_;   // (C,) topological rank at the frame checked, -1 not alive
  std::vector<uint32_t> stamp_; // (C,) search that last visited the collapse
  uint32_t generation_ = 0;
  std::vector<int32_t> stack_;
  std::vector<uint8_t> recheck_;  // (C,) whether the frame checked searches from the collapse
};

// The file through `w`: the header with its length zero, the body, then Writer::finish.
void write_file(const detail::TdagData& d, Writer& w) {
  const auto frame_count = static_cast<size_t>(d.frame_count), vertex_count = static_cast<size_t>(d.vertex_count);
  const size_t per_frame = vertex_count * 3;
  w.raw_array(kMagic, sizeof(kMagic));
  w.raw(kTdagFormatVersion);
  w.raw(uint64_t{0});  // the body's length, below
  w.varint(frame_count);
  w.varint(vertex_count);
  w.varint(d.face_count());
  w.varint(d.collapse_count());
  w.u8(static_cast<uint8_t>(d.affine_base));
  w.u8(static_cast<uint8_t>(d.governing));
  w.zigzag(d.governing_frame);
  w.raw(d.history_weight);
  w.raw(d.scale);
  int32_t previous = 0;
  for (int32_t index : d.faces) {
    w.zigzag(static_cast<int64_t>(index) - previous);
    previous = index;
  }
  // The input vertices' points: a flag for the identity, else each as a delta + 1.
  bool identity = d.input_points.size() == vertex_count;
  for (size_t v = 0; identity && v < vertex_count; ++v) identity = d.input_points[v] == static_cast<int32_t>(v);
  w.varint(d.input_points.size());
  w.u8(identity ? 1 : 0);
  if (!identity) {
    int64_t last = -1;
    for (int32_t point : d.input_points) {
      w.zigzag(static_cast<int64_t>(point) - last);
      last = point;
    }
  }
  const auto two_sided = static_cast<size_t>(std::count(d.two_sided.begin(), d.two_sided.end(), 1));
  w.varint(two_sided);
  int64_t previous_face = -1;
  for (size_t f = 0; f < d.two_sided.size(); ++f)
    if (d.two_sided[f]) {
      w.varint(static_cast<uint64_t>(static_cast<int64_t>(f) - previous_face - 1));
      previous_face = static_cast<int64_t>(f);
    }
  w.raw_array(d.maps.data(), d.maps.size());
  w.raw_array(d.residuals.data(), per_frame);
  std::vector<uint8_t> changed((vertex_count + 7) / 8);
  for (size_t f = 1; f < frame_count; ++f) {
    const float* now = &d.residuals[f * per_frame];
    const float* before = now - per_frame;
    std::fill(changed.begin(), changed.end(), 0);
    for (size_t v = 0; v < vertex_count; ++v)
      if (std::memcmp(now + 3 * v, before + 3 * v, 3 * sizeof(float)) != 0) changed[v / 8] |= uint8_t(1u << (v % 8));
    w.raw_array(changed.data(), changed.size());
    for_each_changed_run(changed, vertex_count, [&](size_t begin, size_t end) {
      w.raw_array(now + 3 * begin, 3 * (end - begin));
      return true;
    });
  }
  detail::ErrorCodeBlock codes(frame_count, d.collapse_count());
  for (size_t c = 0; c < d.collapse_count(); ++c) {
    const int64_t node = static_cast<int64_t>(vertex_count + c);
    if (c % detail::ErrorCodeBlock::kWidth == 0) codes.gather(d.codes_by_frame, c);
    w.varint(static_cast<uint64_t>(node - d.kept_child[c]));
    w.varint(static_cast<uint64_t>(node - d.removed_child[c]));
    w.varint(static_cast<uint64_t>(d.killed[c][0] + 1));
    w.varint(static_cast<uint64_t>(d.killed[c][1] + 1));
    w.tag(d.alive[c]);
    w.varint(static_cast<uint64_t>(d.dep_offsets[c + 1] - d.dep_offsets[c]));
    for (int32_t link = d.dep_offsets[c]; link < d.dep_offsets[c + 1]; ++link) {
      w.zigzag(node - d.dep_nodes[static_cast<size_t>(link)]);
      const TimeTag& tag = d.dep_tags[static_cast<size_t>(link)];
      if (tag == d.alive[c]) {
        w.varint(0);
        continue;
      }
      w.varint(tag.ranges().size() + 1);
      int32_t last = 0;
      for (const FrameRange& r : tag.ranges()) {
        w.varint(static_cast<uint64_t>(r.birth - last));
        w.varint(static_cast<uint64_t>(r.death - r.birth));
        last = r.death;
      }
    }
    uint64_t runs = 0;
    detail::for_each_error_run(codes.column(c), d.frame_count, [&](int32_t, int32_t, uint16_t) { ++runs; });
    w.varint(runs);
    int32_t last_death = 0;
    int32_t last_code = 0;
    detail::for_each_error_run(codes.column(c), d.frame_count, [&](int32_t birth, int32_t death, uint16_t code) {
      const auto gap = static_cast<uint64_t>(birth - last_death);
      w.varint((static_cast<uint64_t>(death - birth - 1) << 1) | (gap > 0 ? 1u : 0u));
      if (gap > 0) w.varint(gap);
      w.zigzag(int32_t(code) - last_code);
      last_death = death;
      last_code = code;
    });
  }
}

// The format version and the body's length from the file's first bytes (`bytes`: at least the
// first min(size, kHeaderSize)), checked against the file's size.
Status read_header(const uint8_t* bytes, size_t size, uint32_t& version, uint64_t& body_size) {
  if (size < sizeof(kMagic) || std::memcmp(bytes, kMagic, sizeof(kMagic)) != 0)
    return Status::error("not a TDAG file (no ANLDTDAG signature)");
  if (size < kHeaderSize) return Status::error("truncated TDAG file (incomplete header)");
  std::memcpy(&version, bytes + 8, 4);
  std::memcpy(&body_size, bytes + 12, 8);
  if (version < kTdagOldestReadableVersion || version > kTdagFormatVersion)
    return Status::error("TDAG format version " + std::to_string(version) +
                         (version < kTdagFormatVersion ? " was written by an older animlod" : " was written by a newer animlod") +
                         "; this build reads versions " + std::to_string(kTdagOldestReadableVersion) + " to " +
                         std::to_string(kTdagFormatVersion) + " (rebuild it with `animlod tdag build`)");
  if (size - kHeaderSize < 4 || body_size != size - kHeaderSize - 4)
    return Status::error("truncated or padded TDAG file: the header announces " + std::to_string(body_size) +
                         " bytes of data, the file holds " + std::to_string(size < kHeaderSize + 4 ? 0 : size - kHeaderSize - 4));
  return Status::success();
}

// The TDAG's fields from its body, whose checksum has been checked.
Status read_body(Reader& r, uint32_t version, std::shared_ptr<const detail::TdagData>& data) {
  auto d = std::make_shared<detail::TdagData>();
  constexpr uint64_t kMaxIndex = INT32_MAX;
  const uint64_t frame_count = r.count("frame count", kMaxIndex - 1);
  const uint64_t vertex_count = r.count("vertex count", kMaxIndex);
  const uint64_t face_count = r.count("face count", kMaxIndex / 3);
  const uint64_t collapse_count = r.count("collapse count", kMaxIndex - vertex_count);
  if (!r.ok()) return Status::error("corrupted TDAG file: " + r.error());
  // Sizes the remaining bytes must at least hold (so that a bad count cannot allocate wildly).
  const uint64_t floor = face_count * 3 + frame_count * 12 * 8 + vertex_count * 12 + collapse_count * 6;
  if (frame_count == 0 || vertex_count == 0 || floor > r.remaining())
    return Status::error("corrupted TDAG file: sizes (F " + std::to_string(frame_count) + ", V " +
                         std::to_string(vertex_count) + ", M " + std::to_string(face_count) + ", C " +
                         std::to_string(collapse_count) + ") do not fit the file");
  d->frame_count = static_cast<int32_t>(frame_count);
  d->vertex_count = static_cast<int32_t>(vertex_count);
  const uint8_t base = r.u8("affine base"), governing = r.u8("governing");
  if (base > static_cast<uint8_t>(AffineBase::average) || governing > static_cast<uint8_t>(Governing::online))
    return Status::error("corrupted TDAG file: unknown affine base or governing mesh");
  d->affine_base = static_cast<AffineBase>(base);
  d->governing = static_cast<Governing>(governing);
  d->governing_frame = static_cast<int32_t>(r.zigzag("governing frame"));
  d->history_weight = r.raw<double>("history weight");
  d->scale = r.raw<double>("scale");
  if (!(d->scale > 0.0) || !std::isfinite(d->scale)) r.fail("scale is not a positive number");
  d->faces.resize(face_count * 3);
  int64_t previous = 0;
  for (auto& index : d->faces) {
    previous += r.zigzag("faces");
    if (previous < 0 || previous >= static_cast<int64_t>(vertex_count)) {
      r.fail("faces: a vertex index outside [0, V)");
      break;
    }
    index = static_cast<int32_t>(previous);
  }
  const uint64_t input_count = r.count("input vertex count", kMaxIndex);
  const uint8_t identity = r.u8("input vertices");
  if (identity > 1 || (identity && input_count != vertex_count)) r.fail("input vertices: bad identity flag");
  if (!identity && input_count > r.remaining()) r.fail("input vertices: count does not fit the file");
  if (r.ok()) {
    d->input_points.resize(input_count);
    int64_t last = -1;
    for (size_t v = 0; v < input_count && r.ok(); ++v) {
      last = identity ? static_cast<int64_t>(v) : last + r.zigzag("input vertices");
      if (last < -1 || last >= static_cast<int64_t>(vertex_count)) r.fail("input vertices: a point outside [0, V)");
      d->input_points[v] = static_cast<int32_t>(last);
    }
  }
  if (version >= 2) {  // version 1 had no two-sided faces
    const uint64_t two_sided = r.count("two-sided face count", face_count);
    if (two_sided > 0 && r.ok()) d->two_sided.assign(face_count, 0);
    int64_t face = -1;
    for (uint64_t i = 0; i < two_sided && r.ok(); ++i) {
      face += static_cast<int64_t>(r.count("two-sided faces", face_count)) + 1;
      if (face >= static_cast<int64_t>(face_count)) r.fail("two-sided faces: a face outside [0, M)");
      else d->two_sided[static_cast<size_t>(face)] = 1;
    }
  }
  d->maps.resize(frame_count * 12);
  r.raw_array(d->maps.data(), d->maps.size(), "affine maps");
  const size_t per_frame = static_cast<size_t>(vertex_count) * 3;
  d->residuals.resize(static_cast<size_t>(frame_count) * per_frame);
  r.raw_array(d->residuals.data(), per_frame, "residuals");
  std::vector<uint8_t> changed((static_cast<size_t>(vertex_count) + 7) / 8);
  for (size_t f = 1; f < frame_count && r.ok(); ++f) {
    float* now = &d->residuals[f * per_frame];
    std::copy_n(now - per_frame, per_frame, now);
    if (!r.raw_array(changed.data(), changed.size(), "residuals")) break;
    for_each_changed_run(changed, vertex_count, [&](size_t begin, size_t end) {
      return r.raw_array(now + 3 * begin, 3 * (end - begin), "residuals");
    });
  }
  for (double value : d->maps)
    if (!std::isfinite(value)) r.fail("a non-finite affine map");
  d->kept_child.resize(collapse_count);
  d->removed_child.resize(collapse_count);
  d->killed.resize(collapse_count);
  d->alive.resize(collapse_count);
  d->dep_offsets.assign(1, 0);
  const auto frames = static_cast<int32_t>(frame_count);
  d->codes_by_frame.assign(frame_count * collapse_count, detail::kNoCode);
  detail::ErrorCodeBlock codes(frame_count, collapse_count);
  for (size_t c = 0; c < collapse_count && r.ok(); ++c) {
    const int64_t node = static_cast<int64_t>(vertex_count + c);
    if (c % detail::ErrorCodeBlock::kWidth == 0) {
      if (c > 0) codes.scatter(d->codes_by_frame);
      codes.start(c);
    }
    d->kept_child[c] = static_cast<int32_t>(node - static_cast<int64_t>(r.count("children", static_cast<uint64_t>(node))));
    d->removed_child[c] = static_cast<int32_t>(node - static_cast<int64_t>(r.count("children", static_cast<uint64_t>(node))));
    for (auto& face : d->killed[c]) face = static_cast<int32_t>(r.count("removed faces", face_count)) - 1;
    d->alive[c] = r.tag("alive tag", frames);
    const uint64_t links = r.count("dependency count", collapse_count);
    for (uint64_t i = 0; i < links && r.ok(); ++i) {
      const int64_t dep = node - r.zigzag("dependencies");
      d->dep_nodes.push_back(static_cast<int32_t>(std::clamp<int64_t>(dep, -1, INT32_MAX)));
      const uint64_t ranges = r.count("dependency tag", frame_count + 1);
      if (ranges == 0) {
        d->dep_tags.push_back(d->alive[c]);
        continue;
      }
      TimeTag tag;
      int64_t last = 0;
      for (uint64_t k = 0; k + 1 < ranges && r.ok(); ++k) {
        const int64_t birth = last + static_cast<int64_t>(r.count("dependency tag", frame_count));
        const int64_t death = birth + static_cast<int64_t>(r.count("dependency tag", frame_count));
        if (death <= birth || death > frames) r.fail("dependency tag: range outside the frames");
        else tag.add({static_cast<int32_t>(birth), static_cast<int32_t>(death)});
        last = death;
      }
      d->dep_tags.push_back(tag);
    }
    d->dep_offsets.push_back(static_cast<int32_t>(d->dep_nodes.size()));
    const uint64_t runs = r.count("error run count", frame_count);
    int64_t death = 0, code = 0;
    uint16_t* column = codes.column(c);
    for (uint64_t i = 0; i < runs && r.ok(); ++i) {
      const uint64_t head = r.varint("error runs");
      if ((head >> 1) >= frame_count) {
        r.fail("error runs: a run longer than the frames");
        break;
      }
      const int64_t birth = death + ((head & 1u) ? static_cast<int64_t>(r.count("error runs", frame_count)) : 0);
      death = birth + static_cast<int64_t>(head >> 1) + 1;
      code += r.zigzag("error runs");
      if (death <= birth || death > frames || code < 0 || code > 65535) {
        r.fail("error runs: a run outside the frames or an invalid code");
        break;
      }
      std::fill(column + birth, column + death, static_cast<uint16_t>(code));
    }
  }
  if (r.ok() && collapse_count > 0) codes.scatter(d->codes_by_frame);
  if (r.ok() && r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " unexpected bytes after the last collapse");
  if (!r.ok()) return Status::error("corrupted TDAG file: " + r.error());
  if (Status status = detail::derive_links(*d); !status) return Status::error("corrupted TDAG file: " + status.message);
  if (Status status = DependencyOrderCheck(*d).run(); !status) return Status::error("corrupted TDAG file: " + status.message);
  data = std::move(d);
  return Status::success();
}

}  // namespace

Status serialize_temporal_dag(const TemporalDag& dag, std::vector<uint8_t>& out) {
  out.clear();
  if (dag.empty()) return Status::error("TemporalDag: empty, nothing to save");
  const detail::TdagData& d = *dag.data_;
  const auto frame_count = static_cast<size_t>(d.frame_count), vertex_count = static_cast<size_t>(d.vertex_count);
  // Reserved for every residual stored (untouched pages cost nothing), so that growing does not
  // copy a long clip's residuals.
  out.reserve(kHeaderSize + d.maps.size() * sizeof(double) +
              frame_count * (vertex_count * 3 * sizeof(float) + vertex_count / 8 + 1) +
              16 * (d.faces.size() + d.input_points.size() + d.dep_nodes.size() +
                    detail::count_error_runs(d.codes_by_frame, frame_count, d.collapse_count())) +
              64 * d.collapse_count() + 1024);
  Writer w(out);
  write_file(d, w);
  w.finish();
  return Status::success();
}

Status write_temporal_dag(const TemporalDag& dag, TdagFileSink& sink, size_t chunk_size) {
  if (dag.empty()) return Status::error("TemporalDag: empty, nothing to save");
  std::vector<uint8_t> buffer;
  buffer.reserve(chunk_size + 64);
  Writer w(buffer, &sink, chunk_size);
  write_file(*dag.data_, w);
  if (!w.finish()) return Status::error("write failed");
  return Status::success();
}

Status deserialize_temporal_dag(const uint8_t* bytes, size_t size, TemporalDag& out) {
  out = TemporalDag{};
  uint32_t version = 0;
  uint64_t body_size = 0;
  if (Status status = read_header(bytes, size, version, body_size); !status) return status;
  const uint8_t* body = bytes + kHeaderSize;
  uint32_t stored_crc = 0;
  std::memcpy(&stored_crc, body + body_size, 4);
  if (detail::crc32(body, static_cast<size_t>(body_size)) != stored_crc)
    return Status::error("corrupted TDAG file: checksum mismatch");
  Reader r(body, static_cast<size_t>(body_size));
  return read_body(r, version, out.data_);
}

Status save_temporal_dag(const TemporalDag& dag, const std::string& path) {
  const std::string temporary = path + ".tmp";
  Status written;
  {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    if (!file) return Status::error(path + ": cannot open for writing");
    struct FileSink : TdagFileSink {
      std::ofstream& file;
      explicit FileSink(std::ofstream& f) : file(f) {}
      bool append(const uint8_t* bytes, size_t size) override {
        return static_cast<bool>(file.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(size)));
      }
      bool overwrite(size_t offset, const uint8_t* bytes, size_t size) override {
        const std::streampos end = file.tellp();
        file.seekp(static_cast<std::streamoff>(offset));
        append(bytes, size);
        return static_cast<bool>(file.seekp(end));
      }
    } sink(file);
    written = write_temporal_dag(dag, sink);
    file.close();
    if (written && !file) written = Status::error("write failed");
  }
  if (!written) {
    std::remove(temporary.c_str());
    return Status::error(path + ": " + written.message);
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::remove(temporary.c_str());
    return Status::error(path + ": " + error.message());
  }
  return Status::success();
}

// Read a chunk at a time, so that the file's bytes (as large as the residuals of a long clip) are
// never held whole.
Status load_temporal_dag(const std::string& path, TemporalDag& out, size_t chunk_size) {
  out = TemporalDag{};
  chunk_size = std::max<size_t>(chunk_size, 1);
  auto fail = [&](const std::string& why) { return Status::error(path + ": " + why); };
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) return fail("a directory, not a TDAG file");
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  const std::streamoff end = file ? static_cast<std::streamoff>(file.tellg()) : -1;
  if (end < 0) return fail("cannot open");
  const auto size = static_cast<size_t>(end);
  file.seekg(0);
  uint8_t header[kHeaderSize];
  file.read(reinterpret_cast<char*>(header), static_cast<std::streamsize>(std::min(size, kHeaderSize)));
  uint32_t version = 0;
  uint64_t body_size = 0;
  if (Status status = read_header(header, size, version, body_size); !status) return fail(status.message);

  std::vector<uint8_t> chunk(chunk_size);
  uint32_t crc = 0;
  for (uint64_t left = body_size; left > 0;) {
    const auto n = static_cast<size_t>(std::min<uint64_t>(left, chunk.size()));
    if (!file.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(n)))
      return fail("truncated TDAG file (it changed while read)");
    crc = detail::crc32(chunk.data(), n, crc);
    left -= n;
  }
  uint32_t stored_crc = 0;
  if (!file.read(reinterpret_cast<char*>(&stored_crc), 4)) return fail("truncated TDAG file (it changed while read)");
  if (crc != stored_crc) return fail("corrupted TDAG file: checksum mismatch");

  file.seekg(static_cast<std::streamoff>(kHeaderSize));
  Reader r(file, body_size, std::move(chunk));
  if (Status status = read_body(r, version, out.data_); !status) return fail(status.message);
  return Status::success();
}

}  // namespace animlod
