// The decoder of the table residual code of stream version 2 (common/table_residual_format.h describes the code).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/range_coder.h"
#include "common/table_residual_format.h"
#include "segmorph/status.h"

namespace segmorph {

// Decodes what encode_table_residuals wrote, a frame at a time. Bad data is sticky: in the range decoder (tables,
// magnitudes) or here (the rANS words); the caller checks failed() after each frame and finish() at the end.
class TableResidualDecoder {
 public:
  // `symbols`: the bytes after the range-coded body (not owned; they must outlive the decoder).
  TableResidualDecoder(size_t welded_count, const uint8_t* symbols, size_t symbol_bytes);

  // The frequency tables, from the body (first, before any frame). Fails on tables a stream may not hold.
  Status read_tables(RangeDecoder& body);

  // The next frame's W × 3 symbols into row[0 .. W × 3).
  void decode_frame(RangeDecoder& body, int64_t* row);

  bool failed() const { return failure_ != nullptr; }

  // The decoder's state between two frames (the tables, which do not change, left out), to come back to it later.
  struct Position {
    size_t next_word = 0;
    std::array<uint32_t, table_code::kStates> state{};
    std::vector<uint8_t> history;
    ExcessModels excess;
    const char* failure = nullptr;
  };
  Position position() const { return {next_word_, state_, history_, excess_, failure_}; }
  void restore(const Position& position);
  // After the last frame: the words consumed exactly, and both states back at their initial value.
  Status finish() const;

 private:
  std::vector<uint32_t> slots_;  // per context and slot, an entry (table_residual_decoder.cpp, slot_entry)
  size_t welded_count_;
  const uint8_t* words_;  // little-endian 16-bit words
  size_t word_count_;
  size_t next_word_ = 0;
  std::array<uint32_t, table_code::kStates> state_{};  // state_[0] decodes the next vertex-frame
  std::vector<uint8_t> history_;                       // per welded vertex: nonzero pattern one frame before
                                                       // (bits 0–2) and two frames before (bits 3–5)
  ExcessModels excess_;
  std::vector<uint32_t> clamped_;  // W: the frame's vertices with a clamped axis (decode_frame)
  const char* failure_ = nullptr;
};

}  // namespace segmorph
