// Reading a whole file for the mesh readers (text.h).
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "io/text.h"

namespace gwnrt::io {
namespace {

// File access

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

std::string errno_text(int err) { return std::error_code(err, std::generic_category()).message(); }

}  // namespace

Status read_whole_file(const std::string& path, std::string& data) {
  std::error_code ec;
  // fopen succeeds on a directory on Linux and only the read fails, with a vaguer message.
  if (std::filesystem::is_directory(path, ec)) {
    return {StatusCode::kIoError, cat(path, ": cannot read: it is a directory")};
  }
  errno = 0;
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "rb"));
  if (!f) {
    const int err = errno;
    return {StatusCode::kIoError, cat(path, ": cannot open: ", err ? errno_text(err) : "unknown error")};
  }
  // The size is only a hint (the file may change, or be a pipe); one spare byte lets the
  // read that meets end-of-file finish without growing the buffer.
  const auto hint = std::filesystem::file_size(path, ec);
  data.resize(ec ? size_t(1) << 16 : static_cast<size_t>(hint) + 1);
  size_t n = 0;
  for (;;) {
    if (n == data.size()) data.resize(data.size() * 2);
    const size_t want = data.size() - n;
    const size_t got = std::fread(data.data() + n, 1, want, f.get());
    n += got;
    if (got < want) break;
  }
  if (std::ferror(f.get())) {
    return {StatusCode::kIoError, cat(path, ": read error: ", errno_text(errno))};
  }
  data.resize(n);
  return Status::Ok();
}

}  // namespace gwnrt::io
