#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <thread>

#include "../../cpp/src/worker_threads.hpp"
#include "animlod/threads.hpp"

namespace {

// How many threads run_workers starts for `requested` threads and 64 tasks.
unsigned workers_started(unsigned requested) {
  std::atomic<unsigned> calls{0};
  animlod::detail::run_workers(requested, 64, [&] { ++calls; });
  return calls.load();
}

}  // namespace

TEST_CASE("threads: the limit caps every parallel loop, and 0 lifts it") {
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  animlod::set_thread_limit(1);
  CHECK(animlod::thread_limit() == 1);
  CHECK(workers_started(0) == 1);
  CHECK(workers_started(8) == 1);  // a request above the limit gets the limit
  animlod::set_thread_limit(1000);
  CHECK(animlod::thread_limit() == hardware);  // never above the hardware threads
  animlod::set_thread_limit(0);
  CHECK(animlod::thread_limit() == hardware);
  CHECK(workers_started(0) == std::min(hardware, 64u));
}
