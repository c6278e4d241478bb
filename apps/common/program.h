// What every gwnrt program does the same way: report a fatal error as "program: message" on
// stderr with exit status 1, check a benchmark's input files up front, and limit TBB to
// --threads workers (0 = all cores).
#pragma once

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include <tbb/global_control.h>

namespace gwnrt::apps {

// Prints "program: message" to stderr; returns the exit status for main to return.
inline int fail(const char* program, const std::string& message) {
  std::fprintf(stderr, "%s: %s\n", program, message.c_str());
  return 1;
}

// The same where returning to main is not practical (deep inside a benchmark's setup).
[[noreturn]] inline void die(const char* program, const std::string& message) { std::exit(fail(program, message)); }

// The first of `paths` that is not a regular file, as "path: no such file" (or "path: not a
// regular file"); "" when all are. A benchmark over several meshes then fails at once, not after
// the meshes before the bad one have run.
inline std::string first_bad_input_file(const std::vector<std::string>& paths) {
  for (const std::string& path : paths) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(path, ec)) continue;
    return path + (std::filesystem::exists(path, ec) ? ": not a regular file" : ": no such file");
  }
  return {};
}

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

}  // namespace gwnrt::apps
