// Decoding of the residual section of a stream: the F × W × 3 residual symbols, in the stream's one range
// coder (spec/entropy-coding.md, section 8, is the bit-exact description).
//
// Most residuals are 0 or ±1, and a vertex's three are often all zero. So each (frame, welded vertex) starts with
// one bit "some residual of this vertex is nonzero"; then each axis codes a nonzero flag (implied for the last axis
// when the first two are zero), a sign, and the magnitude in unary up to 2 (two bits) with an adaptive Exp-Golomb
// escape (UnsignedModel) for magnitudes of 3 and more. Contexts come from the residuals at the same vertex and axis
// in the three previous frames (and, for the nonzero flag, from the earlier axes of the same vertex). A 0 costs at
// most one binary decision and ±1 three, plus the vertex bit shared by three residuals, against 1 and 8 with a
// SignedModel; the decoder's time goes into these decisions, the unpredictable ones above all.
//
// In a lossless stream a residual outside int32, and INT32_MIN itself, is coded as the symbol INT32_MIN (the
// escape) followed by its 64 bits as direct bits, high half first.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "common/range_coder.h"
#include "segmorph/status.h"

namespace segmorph {

// Decodes the symbols encode_residuals wrote, a frame at a time, so that a decoder can turn each frame into positions
// while it is in cache. Problems (an escape in a lossy stream, a magnitude outside int32, a non-canonical escape,
// running past the end of the stream) are the RangeDecoder's sticky flags: the caller checks decoder.failed() after
// a frame and calls decoder.finish() at the end.
struct ResidualModels;
class ResidualDecoder {
 public:
  ResidualDecoder(size_t welded_count, bool lossless);
  ~ResidualDecoder();
  // A copy decodes on from where this one is (its models and history are copied): a checkpoint.
  ResidualDecoder(const ResidualDecoder& other);
  ResidualDecoder& operator=(const ResidualDecoder&) = delete;

  // Bytes a copy holds (for a caller that bounds what its checkpoints take).
  size_t state_bytes() const;

  // The next frame's W × 3 symbols into row[0 .. W × 3).
  void decode_frame(RangeDecoder& decoder, int64_t* row);

 private:
  size_t welded_count_;
  bool lossless_;
  std::unique_ptr<ResidualModels> models_;
  std::vector<uint8_t> history_;  // W × 3, see common/residual_contexts.h (History)
};

// Decodes frame_count × W × 3 symbols written by encode_residuals into `residuals`, which grows a frame at a time
// as the data proves to be there (a few bytes of stream can claim gigabytes of frames). Returns bad_data, and
// stops early, once the stream is known to be bad; the caller still calls decoder.finish() at the end.
Status decode_residuals(RangeDecoder& decoder, size_t welded_count, size_t frame_count, bool lossless,
                        std::vector<int64_t>& residuals);

}  // namespace segmorph
