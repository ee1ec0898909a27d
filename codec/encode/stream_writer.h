// The writer of animation streams (spec/bitstream.md): StreamContent to bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/stream.h"
#include "segmorph/status.h"

namespace segmorph {

// Byte offsets of the parts of an encoded stream, for reports.
struct StreamSizes {
  size_t motion = 0;  // header, welding, labels, motion, weights
  size_t residuals = 0;
};

// Appends the encoded stream to `out`. base: V × 3, as for read_stream (the welding groups come from it).
void write_stream(const StreamContent& content, const std::vector<float>& base, std::vector<uint8_t>& out,
                  StreamSizes* sizes = nullptr);

// The same for a content that may break a rule of the format, as tests of readers need: the symbols up to and
// including the first that breaks a rule the walk checks, then the body's end; returns that rule (ok if none broke).
// write_stream asserts that none does.
Status write_stream_until_invalid(const StreamContent& content, const std::vector<float>& base,
                                  std::vector<uint8_t>& out, StreamSizes* sizes = nullptr);

}  // namespace segmorph
