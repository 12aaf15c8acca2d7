// The core's parallel loops: a worker pool taking tasks from a shared counter (motion re-fit
// chunks, posture-error bones), and fixed contiguous ranges (AQEM's candidate costs, motion
// features' edges).
#pragma once

#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

#include "animlod/threads.hpp"

namespace animlod::detail {

// Runs `worker` on `requested` threads (0: thread_limit()), never on more than thread_limit() or
// `tasks`, and on the calling thread alone when that comes to one.
template <typename Worker>
void run_workers(unsigned requested, size_t tasks, const Worker& worker) {
  const unsigned limit = thread_limit();
  unsigned threads = requested > 0 ? std::min(requested, limit) : limit;
  threads = static_cast<unsigned>(std::min<size_t>(threads, std::max<size_t>(tasks, 1)));
  if (threads <= 1) {
    worker();
    return;
  }
  std::vector<std::thread> pool;
  for (unsigned i = 0; i < threads; ++i) pool.emplace_back(worker);
  for (std::thread& thread : pool) thread.join();
}

// Two workers for `items` of work from `threshold` on, when the thread limit allows two; else
// one: the loops that split their work in halves.
inline size_t halves_from(size_t items, size_t threshold) {
  return items >= threshold && thread_limit() >= 2 ? 2 : 1;
}

// Splits [0, count) into `workers` contiguous ranges and runs range(begin, end, worker) for each,
// the calling thread taking the first.
template <typename Range>
void run_in_ranges(size_t count, size_t workers, const Range& range) {
  workers = std::max<size_t>(workers, 1);
  auto work = [&](size_t worker) { range(count * worker / workers, count * (worker + 1) / workers, worker); };
  std::vector<std::thread> threads;
  for (size_t worker = 1; worker < workers; ++worker) threads.emplace_back(work, worker);
  work(0);
  for (std::thread& thread : threads) thread.join();
}

}  // namespace animlod::detail
