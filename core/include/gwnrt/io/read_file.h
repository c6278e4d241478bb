// Reading a whole file, or standard input, into memory within stated limits (definitions:
// core/src/io/read_file.cpp). The mesh readers and the programs' point and ray files read this
// way. A file may be anything its path names: a pipe, /dev/zero, a stream that never ends; so the
// read stops, with an error naming the file, at a line longer than a limit (text that never ends
// a line) and at more bytes than memory can hold (checked before allocating for a regular file).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "gwnrt/base/status.h"

namespace gwnrt {

// A token read from a file as messages show it: quoted, with bytes that are not printable ASCII
// as '?', cut after 40 characters (it may be binary garbage or a megabyte long).
std::string quoted_token(std::string_view token);

// The line length the mesh readers accept: an OBJ polygon of 5 million corners fits, and reading
// /dev/zero up to it takes a fraction of a second.
inline constexpr uint64_t kMaxMeshLineBytes = uint64_t(64) << 20;

struct ReadLimits {
  // A line (the bytes before a '\n') longer than this ends the read with an error naming the
  // line. Lines are checked as they arrive, so a stream without newlines is not buffered past it.
  uint64_t max_line_bytes = kMaxMeshLineBytes;
  // More bytes than this end the read with an error; 0: available_memory_bytes() (gwnrt/base/memory.h)
  // when the read starts.
  uint64_t max_bytes = 0;
  // For files whose tail may be binary (a PLY's body): called with the bytes read so far, returns
  // kTextNotEnded while it cannot tell, kAllText, or the offset after which lines are not checked.
  // nullptr: the whole file is text.
  size_t (*text_end)(std::string_view head) = nullptr;
};
inline constexpr size_t kTextNotEnded = size_t(-1);
inline constexpr size_t kAllText = size_t(-2);

// The contents of `path` ("-": standard input, named "<stdin>" in messages) into `data`. Fails
// naming the file (and the line, for a line too long) when it is missing, a directory,
// unreadable, or beyond a limit.
Status read_file(const std::string& path, std::string& data, const ReadLimits& limits = {});

// The name messages give `path`: "<stdin>" for "-", else the path itself.
inline std::string source_name(const std::string& path) { return path == "-" ? "<stdin>" : path; }

}  // namespace gwnrt
