// Status: how a library call reports bad data, I/O failure and numerical trouble.
// Caller bugs are asserts; everything that depends on input data comes back as a Status.
#pragma once

#include <string>
#include <utility>

namespace segmorph {

enum class StatusCode {
  ok = 0,
  invalid_argument,  // settings or arguments the caller passed are unusable
  io_error,          // a file could not be read or written
  bad_data,          // the input is malformed: not glTF, out-of-range accessors, truncated streams
  unsupported,       // the input is valid but uses something segmorph does not handle
  nothing_to_do,     // the input is valid but has nothing segmorph can work on (no animation)
  numerical,         // no convergence, singular system
  internal,          // segmorph broke one of its own promises (a bug)
};

class Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}

  static Status Ok() { return Status(); }

  bool ok() const { return code_ == StatusCode::ok; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }

 private:
  StatusCode code_ = StatusCode::ok;
  std::string message_;
};

// Returns early from the enclosing function when `expr` yields a failed Status.
#define SEGMORPH_RETURN_IF_ERROR(expr)                   \
  do {                                                   \
    ::segmorph::Status segmorph_status_ = (expr);        \
    if (!segmorph_status_.ok()) return segmorph_status_; \
  } while (0)

}  // namespace segmorph
