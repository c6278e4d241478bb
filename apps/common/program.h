// What every gwnrt program does the same way: report a fatal error as "program: message" on
// stderr with exit status 1, check a benchmark's input files up front, refuse an output that
// would overwrite an input, write an output whole or not at all, and limit TBB to --threads
// workers (0 = all cores).
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

#include "gwnrt/io/output_file.h"

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

// An output option and its path ("" or "-" for none, or stdout).
struct OutputOption {
  const char* option;
  std::string path;
};

// The first output that is the same file as one of `inputs` (check_output_is_not_input), or the
// same path or file as another output, as "option: message"; "" when none is. Checked before
// any work: `gwnrt-mesh X.obj -o X.obj` had overwritten its input and exited 0.
inline std::string first_output_clash(const std::vector<OutputOption>& outputs,
                                      const std::vector<std::string>& inputs) {
  const auto given = [](const std::string& p) { return !p.empty() && p != "-"; };
  for (size_t i = 0; i < outputs.size(); ++i) {
    if (!given(outputs[i].path)) continue;
    if (Status s = check_output_is_not_input(outputs[i].path, inputs); !s.ok())
      return std::string(outputs[i].option) + ": " + s.message();
    for (size_t j = 0; j < i; ++j) {
      if (!given(outputs[j].path)) continue;
      std::error_code a, b;
      const bool same = std::filesystem::weakly_canonical(outputs[i].path, a) ==
                            std::filesystem::weakly_canonical(outputs[j].path, b) ||
                        std::filesystem::equivalent(outputs[i].path, outputs[j].path, a);
      if (same)
        return std::string(outputs[i].option) + ": " + outputs[i].path + " is also the " + outputs[j].option +
               " output; give each output its own path";
    }
  }
  return {};
}

// Writes an output by `write(FILE*)` (true when every write succeeded) to `path`, or to stdout
// for "-"; a file whole or not at all (ReplacingFile).
template <class Write>
Status write_output(const std::string& path, Write&& write) {
  if (path == "-") {
    const bool ok = write(stdout);
    if (!ok || std::fflush(stdout) != 0) return {StatusCode::kIoError, "<stdout>: write error"};
    return Status::Ok();
  }
  ReplacingFile out(path);
  if (Status s = out.open(); !s.ok()) return s;
  const bool ok = write(out.file());
  return out.commit(ok ? 0 : EIO);
}

// Writes `text` to `path` whole or not at all.
inline Status write_text_file(const std::string& path, const std::string& text) {
  return write_output(path, [&](std::FILE* f) { return std::fwrite(text.data(), 1, text.size(), f) == text.size(); });
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
