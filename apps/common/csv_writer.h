// Buffered CSV output shared by the command-line programs.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <system_error>

namespace gwnrt::apps {

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
  // A position of a recentred program (MeshLoadOptions::recentre): `v` in the model's float
  // coordinates, written as origin + v in the input's coordinates, in double. The text is the
  // shortest fixed-point decimal that reads back to v as point_io reads a position (in double,
  // origin subtracted, rounded to float): a point read from the input comes out as it was
  // written there (512345.678 stays 512345.678, not the 16 or 17 digits of the double origin + v),
  // and no position gets digits beyond those v holds. With a zero origin, or v not finite,
  // exactly field(v).
  void field(float v, double origin) {
    if (origin == 0.0 || !std::isfinite(v)) return field(v);
    const double x = origin + double(v);
    char buf[64], best[64];
    size_t best_size = 0;
    // x with `decimals` (trailing zeros dropped); kept in `best` when it reads back to v.
    const auto reads_back = [&](int decimals) {
      char* end = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::fixed, decimals).ptr;
      if (decimals > 0) {
        while (end[-1] == '0') --end;
        if (end[-1] == '.') --end;
      }
      double y = 0;
      const auto r = std::from_chars(buf, end, y);
      if (r.ec != std::errc() || r.ptr != end || float(y - origin) != v) return false;
      best_size = size_t(end - buf);
      std::memcpy(best, buf, best_size);
      return true;
    };
    // The texts that read back to v are an interval about x, at least a quarter of v's float
    // step (upwards) on either side (a power of 2 has half the step below): decimals of half
    // that step land one in it. Beyond 1e16 fixed-point text is no use; where v holds bits finer
    // than the double x (below about 2^-29 of the origin), no text reads back to it.
    const float a = std::fabs(v);
    const double half_step = (double(std::nextafter(a, HUGE_VALF)) - double(a)) / 2;
    const double decimals = std::ceil(-std::log10(half_step));  // -inf past the largest float
    int hi = decimals <= 0 ? 0 : decimals >= kMaxDecimals ? kMaxDecimals : int(decimals);
    if (!(std::fabs(x) < 1e16) || (!reads_back(hi) && !reads_back(hi = kMaxDecimals))) {
      // The shortest text of the double origin + v.
      best_size = size_t(std::to_chars(best, best + sizeof best, x).ptr - best);
    } else {
      // The fewest decimals, by bisection: reading back is monotone in their count (the nearest
      // text of d + 1 decimals is no farther from x than the nearest of d) but where the
      // interval is not symmetric about x (v a power of 2), where one more may be written.
      int lo = 0;
      while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (reads_back(mid))
          hi = mid;
        else
          lo = mid + 1;
      }
    }
    sep();
    buffer_.append(best, best_size);
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
  static constexpr int kMaxDecimals = 24;
  void sep() {
    if (!first_) buffer_ += ',';
    first_ = false;
  }
  std::FILE* out_;
  std::string buffer_;
  bool first_ = true;
  bool ok_ = true;
};

}  // namespace gwnrt::apps
