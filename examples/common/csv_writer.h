// Buffered CSV output shared by the command-line programs.
#pragma once

#include <charconv>
#include <cstdio>
#include <string>

namespace gwnrt::examples {

// Rows are appended to one growing buffer and written in large blocks: with millions of rows,
// per-value stdio calls would cost more than the evaluation itself.
class CsvWriter {
 public:
  explicit CsvWriter(std::FILE* out) : out_(out) { buffer_.reserve(kFlushBytes + 4096); }

  void field(float v) {
    char buf[32];
    // Shortest representation that parses back to the same float; to_chars writes "inf"/"-inf".
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    sep();
    buffer_.append(buf, r.ptr);
  }
  void field(unsigned v) {
    char buf[16];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    sep();
    buffer_.append(buf, r.ptr);
  }
  void field(const char* text) {
    sep();
    buffer_ += text;
  }
  void end_row() {
    buffer_ += '\n';
    first_ = true;
    if (buffer_.size() >= kFlushBytes) flush();
  }
  bool flush() {
    if (!buffer_.empty() && std::fwrite(buffer_.data(), 1, buffer_.size(), out_) != buffer_.size()) ok_ = false;
    buffer_.clear();
    return ok_;
  }
  bool ok() const { return ok_; }

 private:
  static constexpr size_t kFlushBytes = 1 << 20;
  void sep() {
    if (!first_) buffer_ += ',';
    first_ = false;
  }
  std::FILE* out_;
  std::string buffer_;
  bool first_ = true;
  bool ok_ = true;
};

}  // namespace gwnrt::examples
