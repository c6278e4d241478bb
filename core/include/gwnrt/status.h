// Status-returning public API: a call that can fail returns a Status; ok() says it worked,
// message() says what went wrong in words a user can act on (file, line, element).
#pragma once

#include <string>
#include <utility>

namespace gwnrt {

enum class StatusCode { kOk = 0, kInvalidArgument, kIoError, kParseError, kInvalidMesh, kUnavailable, kInternal };

class Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return {}; }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  explicit operator bool() const { return ok(); }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

}  // namespace gwnrt
