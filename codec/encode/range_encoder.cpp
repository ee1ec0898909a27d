// The encoding side of range_coder.h: the encoder's byte output and the integer models' encode().
#include "common/range_coder.h"

namespace segmorph {
namespace {

// Number of significant bits of `value`: 0 for 0, 32 for values >= 2^31.
int bit_length(uint32_t value) {
  int length = 0;
  while (value != 0) {
    value >>= 1;
    ++length;
  }
  return length;
}

void encode_bit_tree(RangeEncoder& encoder, BitModel* nodes, int bits, uint32_t symbol) {
  uint32_t node = 1;
  for (int i = bits - 1; i >= 0; --i) {
    const uint32_t bit = (symbol >> i) & 1u;
    encoder.encode_bit(nodes[node], bit);
    node = (node << 1) | bit;
  }
}

}  // namespace

// Moves the top byte of the window out of low_. A byte can still change when a later addition carries into it, so
// the newest byte is held in cache_, followed by pending_ff_ bytes of 0xFF that a carry would turn into 0x00. They
// are written once the byte leaving the window shows whether a carry happened (bit 32 of low_ set) or can no longer
// reach them (the byte is below 0xFF).
void RangeEncoder::shift_low() {
  if (low_ < 0xFF000000u || low_ >= (uint64_t(1) << 32)) {
    const uint8_t carry = uint8_t(low_ >> 32);
    // The interval never leaves [0, 1): no carry can reach past the first byte of the stream.
    assert(has_cache_ || carry == 0);
    if (has_cache_) out_.push_back(uint8_t(cache_ + carry));
    for (; pending_ff_ != 0; --pending_ff_) out_.push_back(uint8_t(0xFF + carry));
    cache_ = uint8_t(low_ >> 24);
    has_cache_ = true;
  } else {
    ++pending_ff_;
  }
  low_ = (low_ & 0x00FFFFFFu) << 8;
}

// Picks the smallest value >= low whose low 24 bits are zero. It is less than low + 2^24 <= low + range, so it lies in
// the final interval, and of the final 32-bit window only its top byte needs writing: the decoder reads the other
// three as the implicit zeros. Being the smallest makes the stream unique (the decoder checks code < 2^24).
void RangeEncoder::finish() {
  assert(!finished_);
  finished_ = true;
  low_ = (low_ + 0x00FFFFFFu) & ~uint64_t(0x00FFFFFFu);
  shift_low();  // the top byte of the window into the cache, resolving any carry
  shift_low();  // writes it (low_ is now 0, below 0xFF000000); the zero entering the cache is never written
}

void BitTreeModel::encode(RangeEncoder& encoder, uint32_t symbol) {
  assert((symbol >> bits_) == 0);
  encode_bit_tree(encoder, nodes_.data(), bits_, symbol);
}

void UnsignedModel::encode(RangeEncoder& encoder, uint32_t value) {
  const int length_class = bit_length(value);
  encode_bit_tree(encoder, class_tree_.data(), kUnsignedClassBits, uint32_t(length_class));
  if (length_class < 2) return;  // 0 and 1 are fully described by their class
  encoder.encode_bit(below_leading_[size_t(length_class)], (value >> (length_class - 2)) & 1u);
  const int low_bits = length_class - 2;
  if (low_bits > 0) encoder.encode_direct_bits(value & ((1u << low_bits) - 1u), low_bits);
}

void SignedModel::encode(RangeEncoder& encoder, int32_t value) {
  encoder.encode_bit(nonzero_, value != 0);
  if (value == 0) return;
  encoder.encode_bit(negative_, value < 0);
  // |value| - 1 without overflow: for negative values -(value + 1), which is at most 2^31 - 1.
  const uint32_t magnitude_minus_one = value > 0 ? uint32_t(value) - 1u : uint32_t(-(value + 1));
  magnitude_minus_one_.encode(encoder, magnitude_minus_one);
}

}  // namespace segmorph
