// Outputs that never destroy an input or, on failure, an existing file (gwnrt/io/output_file.h).
#include "gwnrt/io/output_file.h"

#include <atomic>
#include <cerrno>
#include <filesystem>
#include <string>
#include <system_error>
#include <utility>

#ifdef __unix__
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#endif

#include "base/message.h"

namespace gwnrt {

Status check_output_is_not_input(const std::string& output, const std::vector<std::string>& inputs) {
  for (const std::string& input : inputs) {
    std::error_code ec;
    if (std::filesystem::equivalent(output, input, ec) && !ec)
      return {StatusCode::kInvalidArgument,
              cat(output, ": the output is the input ", input,
                  " (the same file), which writing it would destroy; choose another output path")};
  }
  return Status::Ok();
}

ReplacingFile::ReplacingFile(std::string path) : path_(std::move(path)) {}

ReplacingFile::~ReplacingFile() {
  if (file_) std::fclose(file_);
  std::error_code ec;
  if (!temporary_.empty()) std::filesystem::remove(temporary_, ec);
}

Status ReplacingFile::open() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path_, ec);
  target_ = path_;
#ifdef __unix__
  if (!fs::exists(status) || fs::is_regular_file(status)) {
    if (fs::exists(status)) {
      target_ = fs::canonical(path_, ec).string();  // a link's target is what gets replaced
      if (ec) target_ = path_;
    }
    const fs::path destination(target_);
    const fs::path folder = destination.has_parent_path() ? destination.parent_path() : fs::path(".");
    // A unique name beside the destination: the pid and a counter, retried past any left over.
    static std::atomic<uint64_t> counter{0};
    int fd = -1;
    for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
      temporary_ = (folder / cat(".", destination.filename().string(), ".gwnrt-", uint64_t(::getpid()), "-",
                                 counter.fetch_add(1)))
                       .string();
      errno = 0;
      fd = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd < 0 && errno != EEXIST) {
        const int err = errno;
        temporary_.clear();
        return {StatusCode::kIoError, cat(path_, ": cannot open for writing (a file beside it, in ", folder.string(),
                                          "): ", errno_text(err))};
      }
    }
    if (fd < 0) {
      temporary_.clear();
      return {StatusCode::kIoError, cat(path_, ": cannot open for writing: no free temporary name beside it")};
    }
    struct stat existing;
    if (fs::exists(status) && ::stat(target_.c_str(), &existing) == 0) ::fchmod(fd, existing.st_mode & 07777);
    file_ = ::fdopen(fd, "wb");
    if (!file_) {
      const int err = errno;
      ::close(fd);
      return {StatusCode::kIoError, cat(path_, ": cannot open for writing: ", errno_text(err))};
    }
    return Status::Ok();
  }
#endif
  errno = 0;
  file_ = std::fopen(path_.c_str(), "wb");
  if (!file_) return {StatusCode::kIoError, cat(path_, ": cannot open for writing: ", errno_text(errno))};
  return Status::Ok();
}

Status ReplacingFile::commit(int write_error) {
  if (!file_) return {StatusCode::kIoError, cat(path_, ": not open for writing")};
  int error = write_error;
  errno = 0;
  if (std::fflush(file_) != 0 && error == 0) error = errno ? errno : EIO;
  if (std::ferror(file_) && error == 0) error = EIO;
  std::FILE* f = file_;
  file_ = nullptr;
  errno = 0;
  if (std::fclose(f) != 0 && error == 0) error = errno ? errno : EIO;
  if (error != 0) return {StatusCode::kIoError, cat(path_, ": write failed: ", errno_text(error))};
  if (temporary_.empty()) return Status::Ok();
  std::error_code ec;
  std::filesystem::rename(temporary_, target_, ec);
  if (ec) return {StatusCode::kIoError, cat(path_, ": cannot put the written file in place: ", ec.message())};
  temporary_.clear();
  return Status::Ok();
}

}  // namespace gwnrt
