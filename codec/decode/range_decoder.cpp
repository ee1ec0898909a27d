// The decoding side of range_coder.h: the decoder's start and end checks and the integer models' decode().
#include "common/range_coder.h"

namespace segmorph {
namespace {

__attribute__((always_inline)) inline uint32_t decode_bit_tree(RangeDecoder& decoder, BitModel* nodes, int bits) {
  uint32_t node = 1;
  for (int i = 0; i < bits; ++i) node = (node << 1) | decoder.decode_bit(nodes[node]);
  return node - (1u << bits);
}

// UnsignedModel::decode's and SignedModel::decode's bodies, inlined into both those and the run.
__attribute__((always_inline)) inline uint32_t decode_unsigned(RangeDecoder& decoder, BitModel* class_tree,
                                                               BitModel* below_leading) {
  const uint32_t length_class = decode_bit_tree(decoder, class_tree, kUnsignedClassBits);
  if (length_class > uint32_t(kUnsignedMaxClass)) {
    decoder.mark_invalid("range-coded integer is longer than 32 bits");
    return 0;
  }
  if (length_class < 2) return length_class;
  // The leading 1 and the bit below it.
  const uint32_t top_two = 2u | decoder.decode_bit_as_data(below_leading[length_class]);
  const int low_bits = int(length_class) - 2;
  if (low_bits == 0) return top_two;
  return (top_two << low_bits) | decoder.decode_direct_bits(low_bits);
}

__attribute__((always_inline)) inline int32_t decode_signed(RangeDecoder& decoder, BitModel& nonzero,
                                                            BitModel& negative, BitModel* class_tree,
                                                            BitModel* below_leading) {
  if (decoder.decode_bit(nonzero) == 0) return 0;
  const uint32_t is_negative = decoder.decode_bit_as_data(negative);
  const uint32_t magnitude_minus_one = decode_unsigned(decoder, class_tree, below_leading);
  // int32 holds magnitudes up to 2^31 - 1 for positive values and 2^31 for negative ones.
  if (magnitude_minus_one > (is_negative ? 0x7FFFFFFFu : 0x7FFFFFFEu)) {
    decoder.mark_invalid("range-coded signed integer is outside int32");
    return 0;
  }
  return is_negative ? int32_t(-int64_t(magnitude_minus_one) - 1) : int32_t(magnitude_minus_one + 1u);
}

}  // namespace

RangeDecoder::RangeDecoder(const uint8_t* data, size_t size) : data_(data), size_(size) {
  assert(data != nullptr || size == 0);
  for (size_t i = 0; i < kInitialBytes; ++i) code_ = (code_ << 8) | next_byte();
}

Status RangeDecoder::finish() const {
  if (invalid_reason_) return Status(StatusCode::bad_data, invalid_reason_);
  if (overrun()) return Status(StatusCode::bad_data, "range-coded stream is truncated");
  if (position_ < size_ + kImplicitTailBytes)
    return Status(StatusCode::bad_data, "range-coded stream has trailing bytes");
  // The encoder's flush leaves code below 2^24 (see RangeEncoder::finish), which also implies code < range.
  if (code_ >= kRangeTop) return Status(StatusCode::bad_data, "range-coded stream is corrupt");
  return Status::Ok();
}

uint32_t BitTreeModel::decode(RangeDecoder& decoder) {
  return decode_bit_tree(decoder, nodes_.data(), bits_);
}

uint32_t UnsignedModel::decode(RangeDecoder& decoder) {
  return decode_unsigned(decoder, class_tree_.data(), below_leading_.data());
}

int32_t SignedModel::decode(RangeDecoder& decoder) {
  return decode_signed(decoder, nonzero_, negative_, magnitude_minus_one_.class_tree_.data(),
                       magnitude_minus_one_.below_leading_.data());
}

void SignedModel::decode_run(RangeDecoder& decoder, int32_t* out, size_t count) {
  RangeDecoder local(decoder);
  for (size_t i = 0; i < count; ++i)
    out[i] = decode_signed(local, nonzero_, negative_, magnitude_minus_one_.class_tree_.data(),
                           magnitude_minus_one_.below_leading_.data());
  decoder = local;
}

}  // namespace segmorph
