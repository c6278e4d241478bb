// Reading a whole file or stream within limits (gwnrt/io/read_file.h).
#include "gwnrt/io/read_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <system_error>

#include "base/message.h"
#include "gwnrt/base/memory.h"
#include "io/text.h"

namespace gwnrt {

std::string quoted_token(std::string_view token) {
  constexpr size_t kMax = 40;
  std::string s = "'";
  for (size_t i = 0; i < token.size() && i < kMax; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    s += c >= 0x20 && c < 0x7f ? char(c) : '?';
  }
  return s + (token.size() > kMax ? "...'" : "'");
}

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

// Checks the lengths of the lines that end in data[from, to) and of the one still open at `to`,
// as bytes arrive: `line_start` is where the open line began, `line_no` its number.
struct LineCheck {
  uint64_t max_line = 0;
  size_t line_start = 0;
  size_t line_no = 1;
  bool too_long(const std::string& data, size_t from, size_t to) {
    const char* const base = data.data();
    for (size_t at = from; at < to;) {
      const void* nl = std::memchr(base + at, '\n', to - at);
      if (!nl) break;
      const size_t end = size_t(static_cast<const char*>(nl) - base);
      if (end - line_start > max_line) return true;
      line_start = end + 1;
      ++line_no;
      at = end + 1;
    }
    return to - line_start > max_line;
  }
};

Status read_stream(std::FILE* f, const std::string& name, uint64_t size_hint, const ReadLimits& limits,
                   std::string& data) {
  const bool memory_limit = limits.max_bytes == 0;
  const uint64_t max_bytes = memory_limit ? available_memory_bytes() : limits.max_bytes;
  const auto limit_text = [&] {
    return memory_limit ? cat("the ", memory_size_text(max_bytes), " of memory available")
                        : cat("the read limit of ", memory_size_text(max_bytes));
  };
  if (size_hint != kUnknownMemory && size_hint > max_bytes) {
    return {StatusCode::kOutOfMemory,
            cat(name, ": the file is ", memory_size_text(size_hint), ", more than ", limit_text())};
  }
  LineCheck lines{limits.max_line_bytes};
  size_t text_end = limits.text_end ? kTextNotEnded : kAllText;
  // The text's first 64 KiB are checked for control bytes as they arrive: /dev/urandom's newlines
  // keep every line short, so the line limit alone would read it until memory ran out. A text
  // file has none there (a file with them in its comments is refused too).
  constexpr size_t kSniffBytes = size_t(1) << 16;
  size_t sniffed = 0;
  // The hint may be wrong (the file may change) and is none for a stream; one spare byte lets the
  // read that meets the end of a file of the hinted size finish without growing the buffer.
  const uint64_t first = size_hint != kUnknownMemory ? size_hint + 1 : uint64_t(1) << 16;
  data.resize(size_t(std::min(first, saturating_sum(max_bytes, 1))));
  size_t n = 0;
  for (;;) {
    if (n == data.size()) {
      if (n > max_bytes) {
        return {StatusCode::kOutOfMemory, cat(name, ": more than ", limit_text(),
                                              " read without reaching the end (a stream that does not end?)")};
      }
      // At most one byte past the limit: that byte says the limit was passed. While lines are
      // checked, no further than one byte past the longest allowed line either (/dev/zero).
      uint64_t grown = std::min(saturating_product(data.size(), 2), saturating_sum(max_bytes, 1));
      if (text_end == kTextNotEnded || text_end == kAllText)
        grown = std::min(grown, saturating_sum(lines.line_start, saturating_sum(limits.max_line_bytes, 1)));
      data.resize(size_t(grown));
    }
    const size_t want = data.size() - n;
    const size_t got = std::fread(data.data() + n, 1, want, f);
    if (got > 0) {
      if (text_end == kTextNotEnded) text_end = limits.text_end(std::string_view(data.data(), n + got));
      const size_t checked_to =
          text_end == kTextNotEnded || text_end == kAllText ? n + got : std::min(n + got, text_end);
      if (checked_to > n && lines.too_long(data, n, checked_to)) {
        return {StatusCode::kParseError,
                cat(name, ":", lines.line_no, ": line longer than ", memory_size_text(limits.max_line_bytes),
                    " (not a text file, or a stream that never ends a line)")};
      }
      for (const size_t sniff_to = std::min(checked_to, kSniffBytes); sniffed < sniff_to; ++sniffed) {
        // The escape of terminal colours (0x1b) is found in comments; no other binary byte is.
        const char c = data[sniffed];
        if (io::is_binary_byte(c) && c != '\x1b') {
          const size_t line = 1 + size_t(std::count(data.begin(), data.begin() + sniffed, '\n'));
          return {StatusCode::kParseError, cat(name, ":", line, ": ", io::binary_byte_text(c), ": not a text file")};
        }
      }
    }
    n += got;
    if (got < want) break;
  }
  if (std::ferror(f)) return {StatusCode::kIoError, cat(name, ": read error: ", errno_text(errno))};
  data.resize(n);
  return Status::Ok();
}

}  // namespace

Status read_file(const std::string& path, std::string& data, const ReadLimits& limits) {
  return guard_status(source_name(path).c_str(), [&]() -> Status {
    if (path == "-") return read_stream(stdin, source_name(path), kUnknownMemory, limits, data);
    std::error_code ec;
    // fopen succeeds on a directory on Linux and only the read fails, with a vaguer message.
    if (std::filesystem::is_directory(path, ec)) {
      return {StatusCode::kIoError, cat(path, ": cannot read: it is a directory")};
    }
    errno = 0;
    std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "rb"));
    if (!f) {
      const int err = errno;
      return {StatusCode::kIoError, cat(path, ": cannot open: ", errno_text(err))};
    }
    // Only a regular file has a size to check before reading; /dev/zero or a pipe is read as a stream.
    const bool regular = std::filesystem::is_regular_file(path, ec);
    const uint64_t size = regular ? std::filesystem::file_size(path, ec) : kUnknownMemory;
    return read_stream(f.get(), path, ec ? kUnknownMemory : size, limits, data);
  });
}

}  // namespace gwnrt
