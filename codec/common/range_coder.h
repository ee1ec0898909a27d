// Adaptive binary range coder and the integer models built on it: the entropy coder of segmorph streams.
//
// In the spirit of LZMA's coder: a 32-bit range, 11-bit probabilities adapted by a shift of 5, carries propagated
// through a cache byte. Integer arithmetic only, so that an independent decoder (JavaScript) can be written from
// spec/entropy-coding.md alone and produce the same symbols bit for bit. The format constants below are part of that
// specification and are never changed without a new bitstream version.
//
// A stream is the bytes of one RangeEncoder from construction to finish(). Its decoder reads the stream as if it
// were followed by exactly kImplicitTailBytes zero bytes (the encoder leaves them out); a valid stream is consumed
// exactly, to the last of those implicit bytes, and each symbol sequence has exactly one valid stream. finish() thus
// detects trailing bytes always and truncation or damage almost always; the container still records each stream's
// length and the sections their counts.
//
// Models (BitModel and the integer models) hold adaptive probabilities. Encoder and decoder must use the same models
// in the same order with the same history; each model instance owns its contexts. Models are plain values: copy one
// to snapshot its state, construct a new one to reset it.
#pragma once

#include <array>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "segmorph/status.h"

namespace segmorph {

// Format constants (spec/entropy-coding.md, section 2).
constexpr int kProbabilityBits = 11;                          // probabilities are in units of 1/2048
constexpr uint32_t kProbabilityOne = 1u << kProbabilityBits;  // 2048, probability 1.0
constexpr uint16_t kProbabilityInit = kProbabilityOne / 2;    // 1024, probability 0.5
constexpr int kAdaptationShift = 5;                           // each update moves 1/32 of the way to the bit
constexpr uint32_t kRangeTop = 1u << 24;                      // range is kept >= 2^24 between symbols
constexpr size_t kInitialBytes = 4;                           // bytes the decoder reads before the first symbol
constexpr size_t kImplicitTailBytes = 3;                      // zero bytes the encoder leaves out of the stream
constexpr int kMaxDirectBits = 32;                            // per encode/decode_direct_bits call
constexpr int kUnsignedClassBits = 6;                         // bit-tree width of the length class (0..32 valid)
constexpr int kUnsignedMaxClass = 32;                         // bit length of 2^32 - 1
constexpr int kBitTreeMaxBits = 16;                           // widest BitTreeModel

// One adaptive binary context: the probability that the next bit is 0, in units of 1/2048. The update rule keeps it
// within [31, 2017], so neither bit ever has probability 0.
struct BitModel {
  uint16_t prob_zero = kProbabilityInit;

  void update(uint32_t bit) {
    if (bit == 0)
      prob_zero = uint16_t(prob_zero + ((kProbabilityOne - prob_zero) >> kAdaptationShift));
    else
      prob_zero = uint16_t(prob_zero - (prob_zero >> kAdaptationShift));
  }
};

// Writes one stream, appending its bytes to `out` (which must outlive the encoder; bytes already in `out` are kept).
// The last bytes are only known after finish(). Encoding after finish() is a caller bug.
class RangeEncoder {
 public:
  explicit RangeEncoder(std::vector<uint8_t>& out) : out_(out) {}
  RangeEncoder(const RangeEncoder&) = delete;
  RangeEncoder& operator=(const RangeEncoder&) = delete;

  // Codes `bit` (0 or 1) with the probability in `model`, then adapts the model.
  void encode_bit(BitModel& model, uint32_t bit) {
    assert(!finished_ && bit <= 1);
    const uint32_t bound = (range_ >> kProbabilityBits) * model.prob_zero;
    if (bit == 0) {
      range_ = bound;
    } else {
      low_ += bound;
      range_ -= bound;
    }
    model.update(bit);
    if (range_ < kRangeTop) {  // once is enough: the probability bounds keep range >= 2^17 here
      range_ <<= 8;
      shift_low();
    }
  }

  // Codes the low `count` bits of `value` (0 <= count <= 32), most significant first, each with probability 1/2.
  void encode_direct_bits(uint32_t value, int count) {
    assert(!finished_ && count >= 0 && count <= kMaxDirectBits);
    assert(count == 32 || (uint64_t(value) >> count) == 0);
    for (int i = count - 1; i >= 0; --i) {
      range_ >>= 1;
      low_ += range_ & (0u - ((value >> i) & 1u));
      if (range_ < kRangeTop) {
        range_ <<= 8;
        shift_low();
      }
    }
  }

  // Writes the last byte of the stream. Every stream, even one without symbols, is at least one byte long.
  void finish();

 private:
  void shift_low();

  std::vector<uint8_t>& out_;
  uint64_t low_ = 0;  // bits 0..31: the low end of the interval in the current 32-bit window; bit 32: a carry
  uint32_t range_ = 0xFFFFFFFFu;
  uint8_t cache_ = 0;        // the newest byte not yet written, because a carry may still reach it
  bool has_cache_ = false;   // false until the first byte leaves the window
  uint64_t pending_ff_ = 0;  // 0xFF bytes after the cache, also waiting for a possible carry
  bool finished_ = false;
};

// Reads one stream from `size` bytes at `data` (not owned; they must outlive the decoder). Never reads outside
// [data, data + size): positions past the end read as zero. Decoding never fails on the spot; problems are sticky
// flags that finish() reports, so a caller decodes a section and checks once.
class RangeDecoder {
 public:
  RangeDecoder(const uint8_t* data, size_t size);

  // Decodes one bit with the probability in `model`, then adapts the model as the encoder did.
  uint32_t decode_bit(BitModel& model) {
    const uint32_t bound = (range_ >> kProbabilityBits) * model.prob_zero;
    uint32_t bit;
    if (code_ < bound) {
      range_ = bound;
      bit = 0;
    } else {
      code_ -= bound;
      range_ -= bound;
      bit = 1;
    }
    model.update(bit);
    if (range_ < kRangeTop) {
      range_ <<= 8;
      code_ = (code_ << 8) | next_byte();
    }
    return bit;
  }

  // The same as decode_bit, without a branch on the bit: for bits that the caller only uses as data and that are
  // close to a coin toss (a sign, a bit of a number's value). A processor guesses such a branch wrong about half the
  // time, and each wrong guess costs more than the decision; the selects below cost nothing to guess. (In a bit
  // tree the next probability's address waits for the bit either way: a branch there measured faster.)
  uint32_t decode_bit_as_data(BitModel& model) {
    const uint32_t probability = model.prob_zero;
    const uint32_t bound = (range_ >> kProbabilityBits) * probability;
    const uint32_t bit = code_ >= bound ? 1u : 0u;
    const uint32_t mask = 0u - bit;
    code_ -= bound & mask;
    range_ = bound + ((range_ - 2 * bound) & mask);  // range - bound for a 1, bound for a 0 (modulo 2^32)
    const uint32_t after_zero = probability + ((kProbabilityOne - probability) >> kAdaptationShift);
    const uint32_t after_one = probability - (probability >> kAdaptationShift);
    model.prob_zero = uint16_t(after_zero + ((after_one - after_zero) & mask));  // BitModel::update
    if (range_ < kRangeTop) {
      range_ <<= 8;
      code_ = (code_ << 8) | next_byte();
    }
    return bit;
  }

  // Decodes `count` (0 <= count <= 32) equiprobable bits, most significant first.
  uint32_t decode_direct_bits(int count) {
    assert(count >= 0 && count <= kMaxDirectBits);
    uint32_t value = 0;
    for (int i = 0; i < count; ++i) {
      range_ >>= 1;
      const uint32_t bit = code_ >= range_ ? 1u : 0u;
      code_ -= range_ & (0u - bit);
      value = (value << 1) | bit;
      if (range_ < kRangeTop) {
        range_ <<= 8;
        code_ = (code_ << 8) | next_byte();
      }
    }
    return value;
  }

  // True once decoding has needed a byte beyond the stream and its implicit zero bytes: the stream is truncated
  // (or the caller decoded more symbols than were encoded).
  bool overrun() const { return position_ > size_ && position_ - size_ > kImplicitTailBytes; }

  // Records that a decoded symbol is one the format forbids (the models call this; so may callers that check a
  // symbol against their own bounds). `reason` must be a string literal; the first one is kept.
  void mark_invalid(const char* reason) {
    if (!invalid_reason_) invalid_reason_ = reason;
  }

  // True when the stream is already known to be bad: overrun or an invalid symbol. Lets long loops stop early.
  bool failed() const { return invalid_reason_ != nullptr || overrun(); }

  // After the last symbol: ok when no invalid symbol was decoded, the decoder consumed exactly the stream plus its
  // implicit zero bytes, and its final state is the one RangeEncoder::finish() leaves (code < 2^24), so that each
  // symbol sequence has exactly one valid stream. bad_data otherwise, saying whether the stream was truncated, had
  // trailing bytes or was corrupt. A stream cut short can still pass (rarely): callers check lengths and counts too.
  Status finish() const;

  // Bytes consumed so far, counting the implicit zero bytes (and any beyond) that were read past the end.
  size_t position() const { return position_; }

  // The decoder's state between two symbols, to come back to it later (the caller keeps the models' states).
  struct State {
    size_t position;
    uint32_t range, code;
    const char* invalid_reason;
  };
  State state() const { return {position_, range_, code_, invalid_reason_}; }
  void restore(const State& state) {
    position_ = state.position, range_ = state.range, code_ = state.code, invalid_reason_ = state.invalid_reason;
  }

 private:
  // Copied only by the models' runs (SignedModel::decode_run): a local copy's state stays in registers.
  RangeDecoder(const RangeDecoder&) = default;
  RangeDecoder& operator=(const RangeDecoder&) = default;
  friend class SignedModel;

  uint32_t next_byte() {
    const uint32_t byte = position_ < size_ ? data_[position_] : 0u;
    ++position_;
    return byte;
  }

  const uint8_t* data_;
  size_t size_;
  size_t position_ = 0;
  uint32_t range_ = 0xFFFFFFFFu;
  uint32_t code_ = 0;
  const char* invalid_reason_ = nullptr;
};

// Symbols of a fixed alphabet [0, 2^bits), coded most significant bit first, each bit in the context of the bits
// above it (a binary tree of 2^bits - 1 BitModels). Learns any distribution over the alphabet. 0 <= bits <= 16;
// with 0 bits the only symbol is 0 and nothing is coded.
class BitTreeModel {
 public:
  explicit BitTreeModel(int bits) : bits_(bits), nodes_(size_t(1) << bits) {
    assert(bits >= 0 && bits <= kBitTreeMaxBits);
  }

  void encode(RangeEncoder& encoder, uint32_t symbol);
  uint32_t decode(RangeDecoder& decoder);
  int bits() const { return bits_; }

 private:
  int bits_;
  std::vector<BitModel> nodes_;  // 2^bits entries; node 1 is the root, node m's children are 2m and 2m + 1
};

// Unsigned integers of any magnitude in [0, 2^32 - 1], adaptive Exp-Golomb style: the bit length of the value (its
// class, 0..32) through a 6-bit BitTreeModel, the bit below the leading one through a context per class, the
// remaining low bits as direct bits. Decoding a class above 32 marks the decoder invalid and returns 0.
class UnsignedModel {
 public:
  void encode(RangeEncoder& encoder, uint32_t value);
  uint32_t decode(RangeDecoder& decoder);

 private:
  friend class SignedModel;
  std::array<BitModel, 1u << kUnsignedClassBits> class_tree_{};  // nodes 1..63 of the class bit tree
  std::array<BitModel, kUnsignedMaxClass + 1> below_leading_{};  // entries 2..32, by class
};

// Signed integers in [-2^31, 2^31 - 1]: a nonzero flag, a sign (1 = negative) and the magnitude minus one through an
// UnsignedModel, each with its own contexts. Decoding a magnitude outside int32 marks the decoder invalid, returns 0.
class SignedModel {
 public:
  void encode(RangeEncoder& encoder, int32_t value);
  int32_t decode(RangeDecoder& decoder);
  // `count` values in a row into out: the same as count calls of decode(), faster (the decoder's state is kept in
  // registers through the run instead of in memory between calls).
  void decode_run(RangeDecoder& decoder, int32_t* out, size_t count);

 private:
  BitModel nonzero_;
  BitModel negative_;
  UnsignedModel magnitude_minus_one_;
};

}  // namespace segmorph
