// The reader of animation streams (spec/bitstream.md): bytes to StreamContent, whole or a frame at a time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "common/stream.h"
#include "segmorph/status.h"

namespace segmorph {

class RangeDecoder;
class ResidualDecoder;
class TableResidualDecoder;

// Parses a stream whose decoder-side facts are `base` (V × 3 floats): V must match, welding groups come from
// it. Every count is checked against format limits and the data before anything is sized by it.
Status read_stream(const uint8_t* data, size_t size, const std::vector<float>& base, StreamContent& content);

// How many of `frames` frames of `frame_bytes` bytes each a decoder reserves memory for before decoding them
// (growing a frame at a time copies the frames decoded so far at every reallocation): no more than `bound`, as
// many as the data can hold (StreamReader::frame_bound), and at most 64 MiB, because welding lets a short valid
// stream fill many vertices and a damaged one must not allocate gigabytes up front.
size_t frames_to_reserve(size_t frames, size_t bound, size_t frame_bytes);

// read_stream in steps, for a decoder that turns each frame's residuals into positions as they come (in cache, and
// without holding F × W × 3 symbols): read_head() parses everything before the residuals into `content` (which
// must outlive the reader; content.residuals stays empty), read_frame() the next frame's W × 3 residual symbols,
// finish() checks that the stream ends after the last. Each step fails with bad_data as soon as the data is known
// to be bad; then the reader must not be used further.
class StreamReader {
 public:
  StreamReader(const uint8_t* data, size_t size);
  ~StreamReader();
  StreamReader(const StreamReader&) = delete;
  StreamReader& operator=(const StreamReader&) = delete;

  Status read_head(const std::vector<float>& base, StreamContent& content);
  Status read_frame(int64_t* row);
  Status finish() const;

  // After read_head(): the most frames the stream's remaining bytes can hold. Every welded vertex-frame costs
  // at least one binary decision of probability at most 2017/2048 (0.022 bits), so a byte holds at most 364; in
  // the table code a symbol of frequency at most 4032/4096 (table_code::kVertexFramesPerByte per byte).
  // frames_to_reserve() turns it into memory reserved up front.
  size_t frame_bound() const;

  // The reader between two frames, after read_head(): the coders' states, the adaptive models and the residual
  // history, enough to read on from that frame later (restore()). About 3 bytes per welded vertex (1 with the table
  // code) and a few kilobytes.
  struct Checkpoint;
  struct CheckpointDeleter {
    void operator()(Checkpoint* checkpoint) const;
  };
  using CheckpointPointer = std::unique_ptr<Checkpoint, CheckpointDeleter>;
  CheckpointPointer checkpoint() const;
  void restore(const Checkpoint& checkpoint);
  static size_t checkpoint_bytes(const Checkpoint& checkpoint);

 private:
  const uint8_t* data_;
  size_t size_;
  const StreamContent* content_ = nullptr;
  std::unique_ptr<RangeDecoder> decoder_;
  std::unique_ptr<ResidualDecoder> residuals_;
  std::unique_ptr<TableResidualDecoder> table_residuals_;  // instead of residuals_, with kFlagTableResiduals
  size_t body_size_ = 0;                                   // the range-coded body's bytes
};

}  // namespace segmorph
