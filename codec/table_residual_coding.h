// The table residual code of stream version 2 (flag TABLE_RESIDUALS; spec/entropy-coding.md, section 9, is the
// bit-exact description): a lossy stream's residual symbols coded for decoding speed rather than for the last bytes.
//
// The adaptive residual code (residual_coding.h) spends about five binary decisions on a vertex, each one a
// probability lookup, a multiplication and an adaptation in a chain. This code spends one table lookup: each
// (frame, welded vertex) is one symbol of 125, its three residuals clamped to [−2, 2], coded with rANS (asymmetric
// numeral systems, 12-bit frequencies, two interleaved states) from frequency tables the stream carries, one per
// context of 16 (the vertex's nonzero axes in the frame before, and whether any was nonzero two frames before). The
// magnitudes above 2 follow in the range-coded body, where the tables also are; the rANS words follow the body.
// Measured (docs/codec.md): the cow decodes in about two thirds of the time; whole files are 1 to 11 % larger on
// the cow, chicken and horse at --error 0.15 and 0.5.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "range_coder.h"
#include "segmorph/status.h"

namespace segmorph {

namespace table_code {
constexpr int kSymbols = 125;       // 5^3: (x, y, z) clamped to [−2, 2]
constexpr int kContexts = 16;       // nonzero pattern one frame before (8) × any nonzero two before (2)
constexpr int kFrequencyBits = 12;  // frequencies sum to 2^12 in every context
constexpr uint32_t kTotal = 1u << kFrequencyBits;
constexpr uint32_t kMaxFrequency = kTotal - 64;  // 4032: every symbol costs at least 0.021 bits (frame bounds)
constexpr uint32_t kStateLow = 1u << 16;         // rANS states lie in [2^16, 2^32) between symbols
constexpr int kStates = 2;                       // interleaved, vertex-frame by vertex-frame
constexpr int kZeroSymbol = 62;                  // (0, 0, 0)
constexpr size_t kMinSymbolBytes = 4 * kStates;  // the states' initial words
// A byte of the symbol stream holds at most this many vertex-frames (section 9.5 of the spec's Appendix B).
constexpr size_t kVertexFramesPerByte = 376;
}  // namespace table_code

// Codes `residuals` (F × W × 3 lossy quantizer indices in (INT32_MIN, INT32_MAX]; Symbol is int64_t or int32_t, as
// StreamContent holds them): the frequency tables and the
// magnitudes above 2 into `body` (the stream's range coder, after the residual steps), and the rANS words into
// `symbols` (appended; the stream's bytes after the body).
template <typename Symbol>
void encode_table_residuals(RangeEncoder& body, const std::vector<Symbol>& residuals, size_t welded_count,
                            std::vector<uint8_t>& symbols);

// The models of the magnitudes above 2, in the body: per axis, for each residual clamped to ±2, one adaptive bit
// "the magnitude is above 2" and, when it is, the magnitude − 3.
struct ExcessModels {
  std::array<BitModel, 3> above_two;
  std::array<UnsignedModel, 3> minus_three;
};

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
  std::vector<uint32_t> slots_;  // per context and slot, an entry (table_residual_coding.cpp, slot_entry)
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
