// Error reporting for the core: bad data returns a Status naming the element and the reason;
// programmer errors are asserts. Bindings turn a failed Status into a Python ValueError.
#pragma once

#include <string>
#include <utility>

namespace animlod {

struct Status {
  bool ok = true;
  std::string message;  // empty when ok

  static Status success() { return {}; }
  static Status error(std::string why) { return {false, std::move(why)}; }
  explicit operator bool() const { return ok; }
};

}  // namespace animlod
