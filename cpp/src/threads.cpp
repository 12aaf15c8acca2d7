#include "animlod/threads.hpp"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <string>
#include <thread>

namespace animlod {

namespace {

// ANIMLOD_THREADS as it reads now: the cap it sets (0: none), and whether it is set to
// something other than a whole number.
struct EnvironmentCap {
  unsigned threads = 0;
  bool ignored = false;
};

EnvironmentCap read_environment() {
  const char* text = std::getenv("ANIMLOD_THREADS");
  if (!text || !*text) return {};
  const std::string value(text);
  if (value.find_first_not_of("0123456789") != std::string::npos || value.size() > 9) return {0, true};
  return {static_cast<unsigned>(std::stoul(value)), false};
}

std::atomic<unsigned>& setting() {
  static std::atomic<unsigned> cap{read_environment().threads};
  return cap;
}

}  // namespace

bool thread_environment_ignored() { return read_environment().ignored; }

void set_thread_limit(unsigned threads) { setting().store(threads, std::memory_order_relaxed); }

unsigned thread_limit() {
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  const unsigned cap = setting().load(std::memory_order_relaxed);
  return cap == 0 ? hardware : std::min(cap, hardware);
}

}  // namespace animlod
