// The error model (docs/design.md §8): every public function that can fail returns a
// Status; ok() says it worked, message() says what went wrong in words a user can act on (the
// file, line, element or option). [[nodiscard]]: a Status cannot be dropped by accident. Nothing
// throws across a public function: each catches at its boundary (guard_status), allocation
// failures included.
#pragma once

#include <exception>
#include <new>
#include <stdexcept>
#include <string>
#include <utility>

namespace gwnrt {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,
  kIoError,
  kParseError,
  kInvalidMesh,
  kUnavailable,
  kInternal,
  kOutOfMemory
};

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return {}; }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

// Runs fn (returning Status) and turns anything it throws into a Status naming `where`: the one
// place a public function's body meets the standard library's exceptions (std::bad_alloc from a
// vector, std::length_error from a size beyond max_size(), a TBB task's exception).
template <class Fn>
Status guard_status(const char* where, Fn&& fn) noexcept {
  try {
    return std::forward<Fn>(fn)();
  } catch (const std::bad_alloc&) {
    return {StatusCode::kOutOfMemory, std::string(where) + ": out of memory"};
  } catch (const std::length_error& e) {
    return {StatusCode::kOutOfMemory, std::string(where) + ": size beyond what can be allocated (" + e.what() + ")"};
  } catch (const std::exception& e) {
    return {StatusCode::kInternal, std::string(where) + ": " + e.what()};
  } catch (...) {
    return {StatusCode::kInternal, std::string(where) + ": unknown error"};
  }
}

}  // namespace gwnrt
