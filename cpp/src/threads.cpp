#include "animlod/threads.hpp"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <string>
#include <thread>

namespace animlod {

namespace {

unsigned from_environment() {
  const char* text = std::getenv("ANIMLOD_THREADS");
  if (!text || !*text) return 0;
  const std::string value(text);
  if (value.find_first_not_of("0123456789") != std::string::npos || value.size() > 9) return 0;
  return static_cast<unsigned>(std::stoul(value));
}

std::atomic<unsigned>& setting() {
  static std::atomic<unsigned> cap{from_environment()};
  return cap;
}

}  // namespace

void set_thread_limit(unsigned threads) { setting().store(threads, std::memory_order_relaxed); }

unsigned thread_limit() {
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  const unsigned cap = setting().load(std::memory_order_relaxed);
  return cap == 0 ? hardware : std::min(cap, hardware);
}

}  // namespace animlod
