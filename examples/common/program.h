// What every gwnrt program does the same way: report a fatal error as "program: message" on
// stderr with exit status 1, and limit TBB to --threads workers (0 = all cores).
#pragma once

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include <tbb/global_control.h>

namespace gwnrt::examples {

// Prints "program: message" to stderr; returns the exit status for main to return.
inline int fail(const char* program, const std::string& message) {
  std::fprintf(stderr, "%s: %s\n", program, message.c_str());
  return 1;
}

// The same where returning to main is not practical (deep inside a benchmark's setup).
[[noreturn]] inline void die(const char* program, const std::string& message) { std::exit(fail(program, message)); }

// Caps TBB's parallelism for as long as it lives; workers() is the cap in force (the core count
// when threads is 0).
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads) {
    if (threads > 0) limit_.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
  }
  std::size_t workers() const {
    return tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  }

 private:
  std::optional<tbb::global_control> limit_;
};

}  // namespace gwnrt::examples
