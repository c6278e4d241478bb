// Output files that never destroy what the user owns (core/src/io/output_file.cpp): an output
// naming one of the inputs is refused before any work, and a file is written beside its
// destination and renamed over it only once written whole, so a failed or interrupted write
// leaves an existing file as it was.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "gwnrt/base/status.h"

namespace gwnrt {

// Ok unless `output` is the same file as one of `inputs` (device and inode: another spelling of
// its path, a symbolic or a hard link). The error (kInvalidArgument) names both. A path that does
// not exist yet matches nothing.
[[nodiscard]] Status check_output_is_not_input(const std::string& output, const std::vector<std::string>& inputs);

// A file written whole or not at all. open() creates a temporary file in the destination's
// folder (so that the rename stays on one file system; a symbolic link is followed to its
// target, which is what gets replaced, keeping its permissions); commit() flushes, closes and
// renames it into place, checking each step (a full disk is often reported only by the last
// ones); until then the destination is untouched, and the destructor removes the temporary
// file. A destination that exists and is not a regular file (a device, a pipe, /dev/stdout) is
// written in place. Nothing throws; messages name the destination.
class ReplacingFile {
 public:
  explicit ReplacingFile(std::string path);
  ~ReplacingFile();
  ReplacingFile(const ReplacingFile&) = delete;
  ReplacingFile& operator=(const ReplacingFile&) = delete;

  [[nodiscard]] Status open();
  std::FILE* file() const { return file_; }
  // `write_error`: an errno a write already failed with (0: none), reported as the failure.
  [[nodiscard]] Status commit(int write_error = 0);

 private:
  std::string path_;       // the destination as given (for messages)
  std::string target_;     // what the rename replaces: the path, its links followed
  std::string temporary_;  // empty when writing in place
  std::FILE* file_ = nullptr;
};

}  // namespace gwnrt
