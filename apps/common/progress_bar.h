// A stderr progress bar for long batch runs. It polls a counter from a background thread so the
// workers only ever do a relaxed atomic increment; it stays silent when stderr is not a terminal
// so that logs and pipes are not filled with carriage returns.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

namespace gwnrt::apps {

// 1234567 -> "1.2M": counts and rates in progress bars and summaries.
inline std::string human_count(double n) {
  char buf[32];
  if (n >= 1e9)
    std::snprintf(buf, sizeof buf, "%.1fG", n / 1e9);
  else if (n >= 1e6)
    std::snprintf(buf, sizeof buf, "%.1fM", n / 1e6);
  else if (n >= 1e4)
    std::snprintf(buf, sizeof buf, "%.1fk", n / 1e3);
  else
    std::snprintf(buf, sizeof buf, "%.0f", n);
  return buf;
}

class ProgressBar {
 public:
  // `counter` must outlive the bar. `unit` labels the counts ("pts").
  ProgressBar(const std::atomic<size_t>& counter, size_t total, std::string unit = "pts")
      : ProgressBar(counter, total, nullptr, std::move(unit)) {}
  // A total that grows as the work is sized (the mesher learns its passes' sizes one by one).
  ProgressBar(const std::atomic<size_t>& counter, const std::atomic<size_t>& total, std::string unit)
      : ProgressBar(counter, 0, &total, std::move(unit)) {}

  ~ProgressBar() { finish(); }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  bool enabled() const { return enabled_; }

  // Stops the poller and erases the bar; safe to call more than once.
  void finish() {
    if (!enabled_) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stop_) return;
      stop_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
    // Erase rather than leave a 100% bar, so the summary lines that follow start clean.
    if (last_width_ > 0) {
      std::fprintf(stderr, "\r%*s\r", int(last_width_), "");
      std::fflush(stderr);
    }
  }

 private:
  static constexpr int kBarWidth = 30;

  ProgressBar(const std::atomic<size_t>& counter, size_t total, const std::atomic<size_t>* total_counter,
              std::string unit)
      : counter_(counter),
        total_(total),
        total_counter_(total_counter),
        unit_(std::move(unit)),
        enabled_(::isatty(2) == 1) {
    if (!enabled_) return;
    start_ = std::chrono::steady_clock::now();
    thread_ = std::thread([this] { run(); });
  }

  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    // Waiting before the first draw keeps runs that finish quickly free of any bar at all.
    while (!wake_.wait_for(lock, std::chrono::milliseconds(100), [this] { return stop_; })) draw();
  }

  static std::string duration(double seconds) {
    char buf[32];
    const long s = long(seconds + 0.5);
    if (s >= 3600)
      std::snprintf(buf, sizeof buf, "%ldh%02ldm", s / 3600, (s / 60) % 60);
    else if (s >= 60)
      std::snprintf(buf, sizeof buf, "%ldm%02lds", s / 60, s % 60);
    else
      std::snprintf(buf, sizeof buf, "%lds", s);
    return buf;
  }

  void draw() {
    const size_t total = total_counter_ ? total_counter_->load(std::memory_order_relaxed) : total_;
    const size_t done = std::min(counter_.load(std::memory_order_relaxed), total);
    const double fraction = total ? double(done) / double(total) : 1.0;
    const int filled = int(fraction * kBarWidth);
    std::string line = "\r[";
    line.append(size_t(filled), '#');
    line.append(size_t(kBarWidth - filled), ' ');
    char pct[16];
    std::snprintf(pct, sizeof pct, "] %3d%%  ", int(fraction * 100.0));
    line += pct;
    line += human_count(double(done)) + "/" + human_count(double(total)) + " " + unit_;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    // Too few points done (or too little time passed) gives a wildly wrong rate; show nothing yet.
    if (done > 0 && done < total && elapsed > 0.3) {
      line += "  ETA " + duration(elapsed * double(total - done) / double(done));
    }
    const size_t width = line.size() - 1;  // the leading '\r' takes no column
    if (width < last_width_) line.append(last_width_ - width, ' ');
    last_width_ = std::max(last_width_, width);
    std::fputs(line.c_str(), stderr);
    std::fflush(stderr);
  }

  const std::atomic<size_t>& counter_;
  size_t total_;
  const std::atomic<size_t>* total_counter_;
  std::string unit_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  size_t last_width_ = 0;
  std::thread thread_;
};

}  // namespace gwnrt::apps
