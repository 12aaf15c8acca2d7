// The worker pool of the core's parallel loops (motion re-fit chunks, posture-error bones): each
// worker takes tasks from a counter it shares with the others until none is left.
#pragma once

#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace animlod::detail {

// Runs `worker` on `requested` threads (0: every hardware thread), never on more than `tasks`,
// and on the calling thread alone when that comes to one.
template <typename Worker>
void run_workers(unsigned requested, size_t tasks, const Worker& worker) {
  unsigned threads = requested > 0 ? requested : std::max(1u, std::thread::hardware_concurrency());
  threads = static_cast<unsigned>(std::min<size_t>(threads, std::max<size_t>(tasks, 1)));
  if (threads <= 1) {
    worker();
    return;
  }
  std::vector<std::thread> pool;
  for (unsigned i = 0; i < threads; ++i) pool.emplace_back(worker);
  for (std::thread& thread : pool) thread.join();
}

}  // namespace animlod::detail
