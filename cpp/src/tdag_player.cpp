// The double-buffered TDAG player (Shamir and Pascucci 2001, Section 5): two cuts, one read by
// the caller while a second thread updates the other to the next frame; the reading side can
// always fall back on the cheap levels (the affine map, the residual positions) of the cut it
// has. play_temporal_dag measures each level against the input frames.
#include "animlod/tdag_player.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace animlod {

struct TdagPlayer::Impl {
  explicit Impl(const TemporalDag& d) : dag(d), front(d), back(d) {}

  TemporalDag dag;
  TdagCut front;  // owned by the caller's thread
  TdagCut back;   // owned by the update thread while busy, by the caller's thread otherwise
  int32_t next_frame = 0;
  bool started = false;

  std::thread worker;
  std::mutex mutex;
  std::condition_variable changed;
  bool busy = false;        // the update thread is bringing `back` to `target`
  std::atomic<bool> pending{false};  // busy, readable without the lock (for spinning)
  bool stop = false;
  int32_t target = -1;
  int32_t back_frame = -1;  // the frame `back` is at (valid while not busy)

  // The update thread: waits for a target (spinning briefly first, as a frame's handoff is
  // usually a fraction of a millisecond away and a sleeping thread can take far longer to wake).
  void run() {
    while (true) {
      spin_until([&] { return pending.load(std::memory_order_acquire); });
      std::unique_lock<std::mutex> lock(mutex);
      changed.wait(lock, [&] { return stop || busy; });
      if (stop) return;
      const int32_t goal = target;
      lock.unlock();
      back.advance(goal);  // only this thread touches `back` while busy
      lock.lock();
      back_frame = goal;
      busy = false;
      pending.store(false, std::memory_order_release);
      changed.notify_all();
    }
  }

  template <typename Ready>
  static void spin_until(Ready&& ready) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(200);
    while (!ready() && std::chrono::steady_clock::now() < until) std::this_thread::yield();
  }

  // Starts the update of `back` to `frame` when the update thread is idle and `back` is not there.
  void schedule(int32_t frame) {
    std::lock_guard<std::mutex> lock(mutex);
    if (busy || frame >= static_cast<int32_t>(dag.frame_count()) || back_frame == frame) return;
    target = frame;
    busy = true;
    pending.store(true, std::memory_order_release);
    changed.notify_all();
  }

  void wait_idle() {
    spin_until([&] { return !pending.load(std::memory_order_acquire); });
    std::unique_lock<std::mutex> lock(mutex);
    changed.wait(lock, [&] { return !busy; });
  }

  bool ready_for(int32_t frame) {
    std::lock_guard<std::mutex> lock(mutex);
    return !busy && back_frame == frame;
  }

  void shutdown() {
    if (!worker.joinable()) return;
    {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
      pending.store(true, std::memory_order_release);
      changed.notify_all();
    }
    worker.join();
  }
};

TdagPlayer::TdagPlayer(const TemporalDag& dag) : impl_(std::make_unique<Impl>(dag)) {}
TdagPlayer::~TdagPlayer() { impl_->shutdown(); }

Status TdagPlayer::start(double tolerance, int32_t first_frame) {
  Impl& p = *impl_;
  p.wait_idle();
  if (Status status = p.front.query(first_frame, tolerance); !status) return status;
  p.back = p.front;  // the second working cut starts as a copy
  p.back_frame = first_frame;
  p.next_frame = first_frame;
  p.started = true;
  if (!p.worker.joinable()) p.worker = std::thread([&p] { p.run(); });
  p.schedule(first_frame + 1);
  return Status::success();
}

Status TdagPlayer::next(ApproximationLevel level, TdagMesh& out) {
  Impl& p = *impl_;
  if (!p.started) return Status::error("next: the player has not started (call start first)");
  if (done()) return Status::error("next: past the last frame " + std::to_string(p.dag.frame_count() - 1));
  const int32_t frame = p.next_frame;
  if (level == ApproximationLevel::full && p.front.frame() != frame) {
    p.wait_idle();  // from here this thread owns `back` too
    if (p.back_frame != frame) {
      if (Status status = p.back.advance(frame); !status) return status;
      p.back_frame = frame;
    }
    const int32_t old_front = p.front.frame();
    std::swap(p.front, p.back);
    p.back_frame = old_front;
  }
  if (Status status = p.front.approximate(frame, level, out); !status) return status;
  p.next_frame = frame + 1;
  if (!done()) p.schedule(p.next_frame);
  return Status::success();
}

Status TdagPlayer::next_available(TdagMesh& out, ApproximationLevel& used) {
  Impl& p = *impl_;
  if (!p.started) return Status::error("next_available: the player has not started (call start first)");
  used = p.front.frame() == p.next_frame || p.ready_for(p.next_frame) ? ApproximationLevel::full
                                                                    : ApproximationLevel::residual;
  return next(used, out);
}

int32_t TdagPlayer::frame() const { return impl_->next_frame; }
bool TdagPlayer::done() const { return impl_->next_frame >= static_cast<int32_t>(impl_->dag.frame_count()); }

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Largest distance between an input vertex of `frame` and the vertex standing for it.
double vertex_error(const TdagCut& cut, const TdagMesh& mesh, const std::vector<float>& original,
                    std::vector<int32_t>& map) {
  cut.input_vertex_map(map);
  double largest = 0.0;
  for (size_t v = 0; v < map.size(); ++v) {
    const float* a = &original[3 * v];
    const float* b = &mesh.positions[3 * static_cast<size_t>(map[v])];
    const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    largest = std::max(largest, dx * dx + dy * dy + dz * dz);
  }
  return std::sqrt(largest);
}

void add(PlayerLevelStats& stats, std::vector<double>& times, double seconds, double error, const TdagMesh& mesh) {
  times.push_back(seconds);
  stats.mean_seconds += seconds;
  stats.max_seconds = std::max(stats.max_seconds, seconds);
  stats.mean_error += error;
  stats.max_error = std::max(stats.max_error, error);
  stats.mean_vertices += static_cast<double>(mesh.nodes.size());
  stats.mean_faces += static_cast<double>(mesh.faces.size() / 3);
}

void finish(PlayerLevelStats& stats, std::vector<double>& times, int32_t frames) {
  if (!times.empty()) {
    std::nth_element(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(times.size() / 2), times.end());
    stats.median_seconds = times[times.size() / 2];
  }
  const double n = std::max(1, frames);
  stats.mean_seconds /= n;
  stats.mean_error /= n;
  stats.mean_vertices /= n;
  stats.mean_faces /= n;
}

}  // namespace

Status play_temporal_dag(const TemporalDag& dag, const PlayerOptions& options, PlayerReport& out) {
  out = PlayerReport{};
  TdagCut walker(dag), fresh(dag);
  if (Status status = walker.query(options.first_frame, options.tolerance); !status) return status;
  const auto frame_count = static_cast<int32_t>(dag.frame_count());
  const int32_t last = options.frame_count < 0 ? frame_count - 1
                                               : std::min(frame_count - 1, options.first_frame + options.frame_count);
  std::vector<float> original(dag.vertex_count() * 3);
  std::vector<int32_t> map;
  TdagMesh mesh;
  const ApproximationLevel levels[3] = {ApproximationLevel::affine, ApproximationLevel::residual,
                                        ApproximationLevel::full};
  std::vector<double> times[4], update_times, fresh_cut_times;
  for (int32_t t = options.first_frame + 1; t <= last; ++t) {
    if (options.measure_error) dag.frame_positions(t, original.data());
    for (int i = 0; i < 3; ++i) {
      const auto start = Clock::now();
      if (i == 2) {
        if (Status status = walker.advance(t); !status) return status;
        update_times.push_back(seconds_since(start));
      }
      if (Status status = walker.approximate(t, levels[i], mesh); !status) return status;
      const double seconds = seconds_since(start);
      if (i == 2) {
        out.mean_splits += static_cast<double>(walker.last_split_count());
        out.mean_collapses += static_cast<double>(walker.last_collapse_count());
      }
      add(out.levels[i], times[i], seconds, options.measure_error ? vertex_error(walker, mesh, original, map) : 0.0, mesh);
    }
    const auto start = Clock::now();
    if (Status status = fresh.query(t, options.tolerance); !status) return status;
    fresh_cut_times.push_back(seconds_since(start));
    fresh.mesh(mesh);
    const double seconds = seconds_since(start);
    add(out.full_query, times[3], seconds, options.measure_error ? vertex_error(fresh, mesh, original, map) : 0.0, mesh);
    ++out.frames;
  }
  for (int i = 0; i < 3; ++i) finish(out.levels[i], times[i], out.frames);
  finish(out.full_query, times[3], out.frames);
  auto median = [](std::vector<double>& values) {
    if (values.empty()) return 0.0;
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
    return values[values.size() / 2];
  };
  out.median_update_seconds = median(update_times);
  out.median_fresh_cut_seconds = median(fresh_cut_times);
  out.mean_splits /= std::max(1, out.frames);
  out.mean_collapses /= std::max(1, out.frames);

  // The level-3 walk alone: one thread, then double-buffered.
  if (out.frames > 0) {
    TdagCut single(dag);
    if (Status status = single.query(options.first_frame, options.tolerance); !status) return status;
    auto start = Clock::now();
    for (int32_t t = options.first_frame + 1; t <= last; ++t) single.approximate(t, ApproximationLevel::full, mesh);
    out.sequential_seconds_per_frame = seconds_since(start) / out.frames;

    TdagPlayer player(dag);
    if (Status status = player.start(options.tolerance, options.first_frame); !status) return status;
    player.next(ApproximationLevel::full, mesh);  // the first frame, outside the timing
    start = Clock::now();
    while (!player.done() && player.frame() <= last) player.next(ApproximationLevel::full, mesh);
    out.double_buffered_seconds_per_frame = seconds_since(start) / out.frames;
  }
  return Status::success();
}

}  // namespace animlod
