// Status: how a library call reports bad data, I/O failure and numerical trouble. Caller bugs are asserts inside
// the library; everything that depends on input data comes back as a Status, and so does a bad argument at the
// public API (include/segmorph/), whose callers may be other languages. The codes' values are the C API's
// (decoder_c.h): never renumber them.
#pragma once

#include <string>
#include <utility>

namespace segmorph {

enum class StatusCode {
  ok = 0,
  invalid_argument = 1,  // settings or arguments the caller passed are unusable
  io_error = 2,          // a file could not be read or written
  bad_data = 3,          // the input is malformed: not glTF, out-of-range accessors, truncated streams
  unsupported = 4,       // the input is valid but uses something segmorph does not handle
  nothing_to_do = 5,     // the input is valid but has nothing segmorph can work on (no animation)
  numerical = 6,         // no convergence, singular system
  internal = 7,          // segmorph broke one of its own promises (a bug)
  out_of_memory = 8,     // an allocation failed
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
