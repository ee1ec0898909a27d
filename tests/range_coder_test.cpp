#include "common/range_coder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "decode/residual_decoder.h"
#include "encode/residual_encoder.h"

namespace segmorph {
namespace {

// splitmix64: the same numbers on every platform, unlike the standard library's distributions.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  uint32_t next32() { return uint32_t(next() >> 32); }
  uint32_t below(uint32_t n) { return uint32_t((uint64_t(next32()) * n) >> 32); }  // uniform in [0, n)
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }                    // uniform in [0, 1)
  uint32_t bit_with_probability(double p_one) { return uniform() < p_one ? 1u : 0u; }
  // A value whose bit length (0..32) is uniform: every magnitude class equally often.
  uint32_t any_magnitude() {
    const uint32_t length = below(33);
    if (length == 0) return 0;
    const uint32_t top = 1u << (length - 1);
    return top | (next32() & (top - 1));
  }

 private:
  uint64_t state_;
};

// ---------------------------------------------------------------------------------------------------------------
// The decoder (and an encoder) transcribed from spec/entropy-coding.md, written for clarity rather than speed: the
// carry goes back into bytes already written instead of through a cache. The production coder must agree with it
// byte for byte and symbol for symbol, on valid streams and on garbage alike.
namespace reference {

constexpr uint32_t kProbabilityOne = 2048, kProbabilityInit = 1024, kRangeTop = 0x01000000;

struct TraceStep {  // one DecodeBit call, as in the spec's worked example table
  uint32_t prob, range, code, bound, bit, prob_after, range_after, code_after;
  size_t pos_after;
};

struct Decoder {
  const uint8_t* data;
  size_t size;
  size_t pos = 0;
  uint32_t range = 0xFFFFFFFF;
  uint32_t code = 0;
  bool invalid = false;
  std::vector<TraceStep>* trace = nullptr;

  Decoder(const uint8_t* bytes, size_t byte_count) : data(bytes), size(byte_count) {
    for (int i = 0; i < 4; ++i) code = (code << 8) | ReadByte();
  }
  uint32_t ReadByte() {
    const uint32_t byte = pos < size ? data[pos] : 0;
    pos = pos + 1;
    return byte;
  }
  void Normalize() {
    if (range < kRangeTop) {
      range = range << 8;
      code = (code << 8) | ReadByte();
    }
  }
  uint32_t DecodeBit(uint16_t& prob) {
    TraceStep step{prob, range, code, 0, 0, 0, 0, 0, 0};
    const uint32_t bound = (range >> 11) * prob;
    uint32_t bit;
    if (code < bound) {
      range = bound;
      prob = uint16_t(prob + ((kProbabilityOne - prob) >> 5));
      bit = 0;
    } else {
      code = code - bound;
      range = range - bound;
      prob = uint16_t(prob - (prob >> 5));
      bit = 1;
    }
    Normalize();
    step.bound = bound;
    step.bit = bit;
    step.prob_after = prob;
    step.range_after = range;
    step.code_after = code;
    step.pos_after = pos;
    if (trace) trace->push_back(step);
    return bit;
  }
  uint32_t DecodeDirectBits(int count) {
    uint32_t value = 0;
    for (int i = 0; i < count; ++i) {
      range = range >> 1;
      uint32_t bit = 0;
      if (code >= range) {
        code = code - range;
        bit = 1;
      }
      value = value * 2 + bit;
      Normalize();
    }
    return value;
  }
  uint32_t DecodeBitTree(uint16_t* probs, int bits) {
    uint32_t node = 1;
    for (int i = 0; i < bits; ++i) node = node * 2 + DecodeBit(probs[node]);
    return node - (1u << bits);
  }
  bool End() const { return !invalid && pos == size + 3 && code < kRangeTop; }
};

struct Encoder {
  std::vector<uint8_t> out;
  uint64_t low = 0;  // always < 2^32 between calls: carries are applied at once
  uint32_t range = 0xFFFFFFFF;
  int carries = 0;
  int carries_through_ff = 0;  // carries that turned at least one written 0xFF into 0x00

  void Add(uint32_t amount) {
    low += amount;
    if (low >> 32) {
      low &= 0xFFFFFFFF;
      ++carries;
      size_t i = out.size();
      EXPECT_GT(i, 0u) << "carry past the first byte";
      while (i > 0 && out[i - 1] == 0xFF) out[--i] = 0;
      if (i != out.size()) ++carries_through_ff;
      if (i > 0) ++out[i - 1];
    }
  }
  void Normalize() {
    if (range < kRangeTop) {
      out.push_back(uint8_t(low >> 24));
      low = (low << 8) & 0xFFFFFFFF;
      range = range << 8;
    }
  }
  void EncodeBit(uint16_t& prob, uint32_t bit) {
    const uint32_t bound = (range >> 11) * prob;
    if (bit == 0) {
      range = bound;
      prob = uint16_t(prob + ((kProbabilityOne - prob) >> 5));
    } else {
      Add(bound);
      range = range - bound;
      prob = uint16_t(prob - (prob >> 5));
    }
    Normalize();
  }
  void EncodeDirectBits(uint32_t value, int count) {
    for (int i = count - 1; i >= 0; --i) {
      range = range >> 1;
      if ((value >> i) & 1) Add(range);
      Normalize();
    }
  }
  void EncodeBitTree(uint16_t* probs, int bits, uint32_t symbol) {
    uint32_t node = 1;
    for (int i = bits - 1; i >= 0; --i) {
      const uint32_t bit = (symbol >> i) & 1;
      EncodeBit(probs[node], bit);
      node = node * 2 + bit;
    }
  }
  void Finish() {
    Add(uint32_t((kRangeTop - (low & (kRangeTop - 1))) & (kRangeTop - 1)));  // round low up to a multiple of 2^24
    out.push_back(uint8_t(low >> 24));
  }
};

struct UnsignedProbs {
  uint16_t class_tree[64];
  uint16_t below_leading[33];
  UnsignedProbs() {
    for (uint16_t& p : class_tree) p = kProbabilityInit;
    for (uint16_t& p : below_leading) p = kProbabilityInit;
  }
};

uint32_t DecodeUnsigned(Decoder& d, UnsignedProbs& m) {
  const uint32_t c = d.DecodeBitTree(m.class_tree, 6);
  if (c > 32) {
    d.invalid = true;
    return 0;
  }
  if (c < 2) return c;
  const uint32_t top = 2 + d.DecodeBit(m.below_leading[c]);
  if (c == 2) return top;
  return uint32_t(uint64_t(top) * (uint64_t(1) << (c - 2)) + d.DecodeDirectBits(int(c) - 2));
}

void EncodeUnsigned(Encoder& e, UnsignedProbs& m, uint32_t value) {
  uint32_t c = 0;
  while (c < 32 && (value >> c) != 0) ++c;
  e.EncodeBitTree(m.class_tree, 6, c);
  if (c < 2) return;
  e.EncodeBit(m.below_leading[c], (value >> (c - 2)) & 1);
  e.EncodeDirectBits(value & ((1u << (c - 2)) - 1), int(c) - 2);
}

struct SignedProbs {
  uint16_t nonzero = kProbabilityInit;
  uint16_t negative = kProbabilityInit;
  UnsignedProbs magnitude;
};

int32_t DecodeSigned(Decoder& d, SignedProbs& m) {
  if (d.DecodeBit(m.nonzero) == 0) return 0;
  const uint32_t negative = d.DecodeBit(m.negative);
  const int64_t mm = DecodeUnsigned(d, m.magnitude);
  if (negative == 0) {
    if (mm > 2147483646) {
      d.invalid = true;
      return 0;
    }
    return int32_t(mm + 1);
  }
  if (mm > 2147483647) {
    d.invalid = true;
    return 0;
  }
  return int32_t(-mm - 1);
}

void EncodeSigned(Encoder& e, SignedProbs& m, int32_t value) {
  e.EncodeBit(m.nonzero, value != 0);
  if (value == 0) return;
  e.EncodeBit(m.negative, value < 0);
  EncodeUnsigned(e, m.magnitude, uint32_t(std::abs(int64_t(value)) - 1));
}

// Section 8: the residual symbols. r is F × W × 3, decoded in place; no early exit, as in the pseudocode.
struct ResidualAxisProbs {
  uint16_t nonzero[36], negative[9], above_one[9], above_two[9];
  UnsignedProbs magnitude;
  ResidualAxisProbs() {
    for (uint16_t& p : nonzero) p = kProbabilityInit;
    for (uint16_t& p : negative) p = kProbabilityInit;
    for (uint16_t& p : above_one) p = kProbabilityInit;
    for (uint16_t& p : above_two) p = kProbabilityInit;
  }
};

struct ResidualProbs {
  uint16_t vertex[64];
  ResidualAxisProbs axis[3];
  ResidualProbs() {
    for (uint16_t& p : vertex) p = kProbabilityInit;
  }
};

uint32_t Z(int64_t v) {
  return v != 0 ? 1 : 0;
}
uint32_t Q(int64_t v) {
  return v == 0 ? 0 : (v == 1 || v == -1) ? 1 : 2;
}
uint32_t T(int64_t v) {
  return v == 0 ? 0 : v > 0 ? 1 : 2;
}

int64_t DecodeResidual(Decoder& d, ResidualAxisProbs& m, uint32_t nonzero_context, uint32_t negative_context,
                       uint32_t magnitude_context, bool nonzero_implied, bool lossless) {
  if (!nonzero_implied && d.DecodeBit(m.nonzero[nonzero_context]) == 0) return 0;
  const uint32_t negative = d.DecodeBit(m.negative[negative_context]);
  uint32_t magnitude = 1;
  if (d.DecodeBit(m.above_one[magnitude_context]) == 1) {
    magnitude = 2;
    if (d.DecodeBit(m.above_two[magnitude_context]) == 1) {
      const uint32_t rest = DecodeUnsigned(d, m.magnitude);
      if (rest > (negative == 1 ? 2147483648u - 3 : 2147483647u - 3)) {
        d.invalid = true;
        return 0;
      }
      magnitude = rest + 3;
    }
  }
  if (negative == 1 && magnitude == 2147483648u) {
    if (!lossless) {
      d.invalid = true;
      return 0;
    }
    const uint64_t high = d.DecodeDirectBits(32);
    const uint64_t low = d.DecodeDirectBits(32);
    const int64_t value = int64_t(high * 4294967296u + low);
    if (-2147483648ll < value && value <= 2147483647) d.invalid = true;
    return value;
  }
  return negative == 1 ? -int64_t(magnitude) : int64_t(magnitude);
}

// `after_vertex`, when given, receives (range, code, pos) after each vertex of each frame.
struct DecoderState {
  uint32_t range, code;
  size_t pos;
};

void DecodeResidualSection(Decoder& d, size_t W, bool lossless, std::vector<int64_t>& r,
                           std::vector<DecoderState>* after_vertex = nullptr) {
  ResidualProbs models;
  const size_t F = r.size() / (3 * W);
  auto R = [&](size_t f, size_t back, size_t w, size_t a) -> int64_t {
    return f < back ? 0 : r[((f - back) * W + w) * 3 + a];
  };
  for (size_t f = 0; f < F; f++) {
    for (size_t w = 0; w < W; w++) {
      uint32_t n[4] = {0, 0, 0, 0};
      for (size_t k = 1; k <= 3; k++) n[k] = Z(R(f, k, w, 0)) + Z(R(f, k, w, 1)) + Z(R(f, k, w, 2));
      int64_t* v = &r[(f * W + w) * 3];
      if (d.DecodeBit(models.vertex[16 * n[1] + 4 * n[2] + n[3]]) == 0) {
        v[0] = v[1] = v[2] = 0;
      } else {
        for (size_t a = 0; a < 3; a++) {
          const int64_t p1 = R(f, 1, w, a), p2 = R(f, 2, w, a), p3 = R(f, 3, w, a);
          const uint32_t e = (a >= 1 && v[0] != 0) || (a == 2 && v[1] != 0);
          v[a] = DecodeResidual(d, models.axis[a], 2 * (2 * (3 * Q(p1) + Q(p2)) + Z(p3)) + e, 3 * T(p1) + T(p2),
                                3 * Q(p1) + Q(p2), a == 2 && e == 0, lossless);
        }
      }
      if (after_vertex) after_vertex->push_back({d.range, d.code, d.pos});
    }
  }
}

}  // namespace reference

// ---------------------------------------------------------------------------------------------------------------
// A schedule of mixed symbols over several contexts, coded by the production models and by the reference.

enum class Kind { bit, direct, unsigned_int, signed_int, tree };

struct Symbol {
  Kind kind;
  int context;     // which model of its kind; for direct bits, the bit count
  uint32_t value;  // signed values as their two's complement bits
};

constexpr int kBitContexts = 4;
constexpr double kBitContextProbabilityOne[kBitContexts] = {0.5, 0.1, 0.01, 0.97};
constexpr int kTreeBits[] = {0, 3, 8};

struct Models {
  std::vector<BitModel> bits = std::vector<BitModel>(kBitContexts);
  std::vector<UnsignedModel> unsigneds = std::vector<UnsignedModel>(2);
  std::vector<SignedModel> signeds = std::vector<SignedModel>(2);
  std::vector<BitTreeModel> trees = {BitTreeModel(kTreeBits[0]), BitTreeModel(kTreeBits[1]),
                                     BitTreeModel(kTreeBits[2])};
};

struct ReferenceModels {
  uint16_t bits[kBitContexts] = {1024, 1024, 1024, 1024};
  reference::UnsignedProbs unsigneds[2];
  reference::SignedProbs signeds[2];
  std::vector<std::vector<uint16_t>> trees = {std::vector<uint16_t>(1, 1024), std::vector<uint16_t>(8, 1024),
                                              std::vector<uint16_t>(256, 1024)};
};

void encode_symbol(RangeEncoder& encoder, Models& models, const Symbol& symbol) {
  switch (symbol.kind) {
    case Kind::bit:
      encoder.encode_bit(models.bits[size_t(symbol.context)], symbol.value);
      break;
    case Kind::direct:
      encoder.encode_direct_bits(symbol.value, symbol.context);
      break;
    case Kind::unsigned_int:
      models.unsigneds[size_t(symbol.context)].encode(encoder, symbol.value);
      break;
    case Kind::signed_int:
      models.signeds[size_t(symbol.context)].encode(encoder, int32_t(symbol.value));
      break;
    case Kind::tree:
      models.trees[size_t(symbol.context)].encode(encoder, symbol.value);
      break;
  }
}

uint32_t decode_symbol(RangeDecoder& decoder, Models& models, const Symbol& symbol) {
  switch (symbol.kind) {
    case Kind::bit:
      return decoder.decode_bit(models.bits[size_t(symbol.context)]);
    case Kind::direct:
      return decoder.decode_direct_bits(symbol.context);
    case Kind::unsigned_int:
      return models.unsigneds[size_t(symbol.context)].decode(decoder);
    case Kind::signed_int:
      return uint32_t(models.signeds[size_t(symbol.context)].decode(decoder));
    case Kind::tree:
      return models.trees[size_t(symbol.context)].decode(decoder);
  }
  return 0;
}

void reference_encode_symbol(reference::Encoder& encoder, ReferenceModels& models, const Symbol& symbol) {
  const size_t context = size_t(symbol.context);
  switch (symbol.kind) {
    case Kind::bit:
      encoder.EncodeBit(models.bits[context], symbol.value);
      break;
    case Kind::direct:
      encoder.EncodeDirectBits(symbol.value, symbol.context);
      break;
    case Kind::unsigned_int:
      reference::EncodeUnsigned(encoder, models.unsigneds[context], symbol.value);
      break;
    case Kind::signed_int:
      reference::EncodeSigned(encoder, models.signeds[context], int32_t(symbol.value));
      break;
    case Kind::tree:
      encoder.EncodeBitTree(models.trees[context].data(), kTreeBits[context], symbol.value);
      break;
  }
}

uint32_t reference_decode_symbol(reference::Decoder& decoder, ReferenceModels& models, const Symbol& symbol) {
  const size_t context = size_t(symbol.context);
  switch (symbol.kind) {
    case Kind::bit:
      return decoder.DecodeBit(models.bits[context]);
    case Kind::direct:
      return decoder.DecodeDirectBits(symbol.context);
    case Kind::unsigned_int:
      return reference::DecodeUnsigned(decoder, models.unsigneds[context]);
    case Kind::signed_int:
      return uint32_t(reference::DecodeSigned(decoder, models.signeds[context]));
    case Kind::tree:
      return decoder.DecodeBitTree(models.trees[context].data(), kTreeBits[context]);
  }
  return 0;
}

std::vector<Symbol> random_schedule(Random& random, size_t count) {
  std::vector<Symbol> schedule;
  for (size_t i = 0; i < count; ++i) {
    Symbol symbol{};
    switch (random.below(8)) {
      case 0:
      case 1:
      case 2:
      case 3:
        symbol.kind = Kind::bit;
        symbol.context = int(random.below(kBitContexts));
        symbol.value = random.bit_with_probability(kBitContextProbabilityOne[symbol.context]);
        break;
      case 4:
        symbol.kind = Kind::direct;
        symbol.context = int(random.below(33));
        symbol.value = symbol.context == 0 ? 0 : random.next32() >> (32 - symbol.context);
        break;
      case 5:
        symbol.kind = Kind::unsigned_int;
        symbol.context = int(random.below(2));
        symbol.value = symbol.context == 0 ? random.below(40) : random.any_magnitude();
        break;
      case 6:
        symbol.kind = Kind::signed_int;
        symbol.context = int(random.below(2));
        symbol.value = symbol.context == 0 ? random.below(9) - 4 : random.next32() >> random.below(32);
        break;
      default:
        symbol.kind = Kind::tree;
        symbol.context = int(random.below(3));
        symbol.value = random.below(std::min(1u << kTreeBits[symbol.context], random.below(4) == 0 ? 256u : 3u));
        break;
    }
    schedule.push_back(symbol);
  }
  return schedule;
}

std::vector<uint8_t> encode_schedule(const std::vector<Symbol>& schedule) {
  std::vector<uint8_t> bytes;
  RangeEncoder encoder(bytes);
  Models models;
  for (const Symbol& symbol : schedule) encode_symbol(encoder, models, symbol);
  encoder.finish();
  return bytes;
}

// Decoded values, with the decoder's position after each symbol.
struct Decoded {
  std::vector<uint32_t> values;
  std::vector<size_t> positions;
  Status status;
  bool overrun = false;
};

// Decodes from an exactly sized heap copy, so that AddressSanitizer sees any read past the end.
Decoded decode_schedule(const uint8_t* data, size_t size, const std::vector<Symbol>& schedule) {
  const std::unique_ptr<uint8_t[]> copy(size ? new uint8_t[size] : nullptr);
  if (size) std::copy(data, data + size, copy.get());
  RangeDecoder decoder(copy.get(), size);
  Models models;
  Decoded decoded;
  for (const Symbol& symbol : schedule) {
    decoded.values.push_back(decode_symbol(decoder, models, symbol));
    decoded.positions.push_back(decoder.position());
  }
  decoded.status = decoder.finish();
  decoded.overrun = decoder.overrun();
  return decoded;
}

Decoded decode_schedule(const std::vector<uint8_t>& bytes, const std::vector<Symbol>& schedule) {
  return decode_schedule(bytes.data(), bytes.size(), schedule);
}

std::vector<uint32_t> values_of(const std::vector<Symbol>& schedule) {
  std::vector<uint32_t> values;
  for (const Symbol& symbol : schedule) values.push_back(symbol.value);
  return values;
}

// ---------------------------------------------------------------------------------------------------------------
// Round trips.

TEST(RangeCoder, StreamWithoutSymbolsIsOneByteAndDecodes) {
  std::vector<uint8_t> bytes;
  RangeEncoder encoder(bytes);
  encoder.finish();
  ASSERT_EQ(bytes, std::vector<uint8_t>{0x00});
  RangeDecoder decoder(bytes.data(), bytes.size());
  EXPECT_TRUE(decoder.finish().ok());
}

TEST(RangeCoder, SkewedBitsRoundTrip) {
  Random random(1);
  for (double p_one : {0.5, 0.3, 0.1, 0.05, 0.01, 0.001, 0.0, 0.999, 1.0}) {
    std::vector<uint32_t> bits;
    for (int i = 0; i < 20000; ++i) bits.push_back(random.bit_with_probability(p_one));
    std::vector<uint8_t> bytes;
    RangeEncoder encoder(bytes);
    BitModel encode_model;
    for (uint32_t bit : bits) encoder.encode_bit(encode_model, bit);
    encoder.finish();

    RangeDecoder decoder(bytes.data(), bytes.size());
    BitModel decode_model;
    std::vector<uint32_t> decoded;
    for (size_t i = 0; i < bits.size(); ++i) decoded.push_back(decoder.decode_bit(decode_model));
    EXPECT_EQ(decoded, bits) << "p(1) = " << p_one;
    EXPECT_TRUE(decoder.finish().ok()) << "p(1) = " << p_one << ": " << decoder.finish().message();
    EXPECT_EQ(decode_model.prob_zero, encode_model.prob_zero);
  }
}

TEST(RangeCoder, ProbabilityStaysWithinItsBounds) {
  BitModel model;
  for (int i = 0; i < 1000; ++i) model.update(0);
  EXPECT_EQ(model.prob_zero, 2017);
  for (int i = 0; i < 1000; ++i) model.update(1);
  EXPECT_EQ(model.prob_zero, 31);
}

TEST(RangeCoder, DirectBitsRoundTripEveryWidth) {
  Random random(2);
  std::vector<Symbol> schedule;
  for (int count = 0; count <= 32; ++count) {
    const uint32_t all_ones = count == 0 ? 0u : 0xFFFFFFFFu >> (32 - count);
    for (uint32_t value : {0u, all_ones, all_ones & random.next32(), all_ones & random.next32()}) {
      schedule.push_back({Kind::bit, 3, random.bit_with_probability(0.97)});  // vary the coder's state in between
      schedule.push_back({Kind::direct, count, value});
    }
  }
  const Decoded decoded = decode_schedule(encode_schedule(schedule), schedule);
  EXPECT_EQ(decoded.values, values_of(schedule));
  EXPECT_TRUE(decoded.status.ok()) << decoded.status.message();
}

TEST(RangeCoder, UnsignedRoundTripEveryMagnitude) {
  std::vector<Symbol> schedule;
  Random random(3);
  for (int length = 0; length <= 32; ++length) {
    const uint32_t smallest = length == 0 ? 0u : 1u << (length - 1);
    const uint32_t largest = length == 0 ? 0u : uint32_t((uint64_t(1) << length) - 1);
    for (uint32_t value : {smallest, largest, smallest | (random.next32() & (largest >> 1))})
      for (int context = 0; context < 2; ++context) schedule.push_back({Kind::unsigned_int, context, value});
  }
  for (uint32_t value : {0u, 1u, 2u, 3u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFEu, 0xFFFFFFFFu})
    schedule.push_back({Kind::unsigned_int, 1, value});
  const Decoded decoded = decode_schedule(encode_schedule(schedule), schedule);
  EXPECT_EQ(decoded.values, values_of(schedule));
  EXPECT_TRUE(decoded.status.ok()) << decoded.status.message();
}

TEST(RangeCoder, SignedRoundTripExtremes) {
  std::vector<Symbol> schedule;
  Random random(4);
  const int32_t extremes[] = {0,
                              1,
                              -1,
                              2,
                              -2,
                              1000,
                              -1000,
                              std::numeric_limits<int32_t>::max(),
                              std::numeric_limits<int32_t>::min(),
                              std::numeric_limits<int32_t>::max() - 1,
                              std::numeric_limits<int32_t>::min() + 1};
  for (int32_t value : extremes) schedule.push_back({Kind::signed_int, 1, uint32_t(value)});
  for (int i = 0; i < 2000; ++i) {
    const int32_t magnitude = int32_t(random.any_magnitude() >> 1);
    schedule.push_back({Kind::signed_int, i % 2, uint32_t(random.below(2) ? magnitude : -magnitude)});
  }
  const Decoded decoded = decode_schedule(encode_schedule(schedule), schedule);
  EXPECT_EQ(decoded.values, values_of(schedule));
  EXPECT_TRUE(decoded.status.ok()) << decoded.status.message();
}

TEST(RangeCoder, BitTreeRoundTripEveryWidth) {
  Random random(5);
  for (int bits = 0; bits <= kBitTreeMaxBits; ++bits) {
    std::vector<uint32_t> symbols;
    const uint32_t alphabet_mask = (1u << bits) - 1u;
    for (int i = 0; i < 3000; ++i) symbols.push_back(random.next32() & alphabet_mask >> (i % 3 == 0 ? 0 : bits / 2));
    symbols.push_back(bits == 0 ? 0u : (1u << bits) - 1u);
    std::vector<uint8_t> bytes;
    RangeEncoder encoder(bytes);
    BitTreeModel encode_model(bits);
    for (uint32_t symbol : symbols) encode_model.encode(encoder, symbol);
    encoder.finish();
    RangeDecoder decoder(bytes.data(), bytes.size());
    BitTreeModel decode_model(bits);
    std::vector<uint32_t> decoded;
    for (size_t i = 0; i < symbols.size(); ++i) decoded.push_back(decode_model.decode(decoder));
    EXPECT_EQ(decoded, symbols) << bits << " bits";
    EXPECT_TRUE(decoder.finish().ok()) << bits << " bits";
  }
}

TEST(RangeCoder, MixedSchedulesRoundTrip) {
  for (uint64_t seed = 10; seed < 40; ++seed) {
    Random random(seed);
    const std::vector<Symbol> schedule = random_schedule(random, 3000);
    const Decoded decoded = decode_schedule(encode_schedule(schedule), schedule);
    EXPECT_EQ(decoded.values, values_of(schedule)) << "seed " << seed;
    EXPECT_TRUE(decoded.status.ok()) << "seed " << seed << ": " << decoded.status.message();
  }
}

TEST(RangeCoder, EncodingIsDeterministicAndAppends) {
  Random random(6);
  const std::vector<Symbol> schedule = random_schedule(random, 5000);
  const std::vector<uint8_t> first = encode_schedule(schedule);
  EXPECT_EQ(encode_schedule(schedule), first);

  std::vector<uint8_t> bytes = {0xAB, 0xCD};
  RangeEncoder encoder(bytes);
  Models models;
  for (const Symbol& symbol : schedule) encode_symbol(encoder, models, symbol);
  encoder.finish();
  ASSERT_EQ(bytes.size(), first.size() + 2);
  EXPECT_EQ(bytes[0], 0xAB);
  EXPECT_EQ(bytes[1], 0xCD);
  EXPECT_TRUE(std::equal(first.begin(), first.end(), bytes.begin() + 2));
}

// ---------------------------------------------------------------------------------------------------------------
// Agreement with the specification's pseudocode.

TEST(RangeCoderSpec, ReferenceEncoderWritesTheSameBytesIncludingCarries) {
  int carries = 0, carries_through_ff = 0;
  for (uint64_t seed = 100; seed < 160; ++seed) {
    Random random(seed);
    const std::vector<Symbol> schedule = random_schedule(random, 4000);
    reference::Encoder encoder;
    ReferenceModels models;
    for (const Symbol& symbol : schedule) reference_encode_symbol(encoder, models, symbol);
    encoder.Finish();
    EXPECT_EQ(encode_schedule(schedule), encoder.out) << "seed " << seed;
    carries += encoder.carries;
    carries_through_ff += encoder.carries_through_ff;
  }
  // The comparison above covers the cache and its pending 0xFF bytes only if carries happened, some through 0xFF.
  EXPECT_GT(carries, 100);
  EXPECT_GT(carries_through_ff, 0);
}

TEST(RangeCoderSpec, ReferenceDecoderAgreesOnValidStreams) {
  for (uint64_t seed = 200; seed < 230; ++seed) {
    Random random(seed);
    const std::vector<Symbol> schedule = random_schedule(random, 3000);
    const std::vector<uint8_t> bytes = encode_schedule(schedule);
    reference::Decoder decoder(bytes.data(), bytes.size());
    ReferenceModels models;
    std::vector<uint32_t> values;
    for (const Symbol& symbol : schedule) values.push_back(reference_decode_symbol(decoder, models, symbol));
    EXPECT_EQ(values, values_of(schedule)) << "seed " << seed;
    EXPECT_TRUE(decoder.End()) << "seed " << seed;
  }
}

// The worked example of spec/entropy-coding.md: the symbols, the bytes, and the decoder's first steps.
std::vector<Symbol> worked_example() {
  std::vector<Symbol> schedule;
  for (uint32_t bit : {0, 0, 1, 0, 0, 0, 0, 1, 0, 0}) schedule.push_back({Kind::bit, 0, bit});
  for (uint32_t value : {5u, 0u, 1000u}) schedule.push_back({Kind::unsigned_int, 0, value});
  for (int32_t value : {-3, 70000}) schedule.push_back({Kind::signed_int, 0, uint32_t(value)});
  schedule.push_back({Kind::tree, 1, 6});  // a 3-bit tree
  schedule.push_back({Kind::direct, 10, 0x2A5});
  return schedule;
}

const std::vector<uint8_t> kWorkedExampleBytes = {0x24, 0x84, 0x6D, 0xC6, 0x0C, 0x88, 0xDE, 0x3A, 0x13, 0x5B, 0x63};

TEST(RangeCoderSpec, WorkedExampleIsAGoldenVector) {
  const std::vector<Symbol> schedule = worked_example();
  EXPECT_EQ(encode_schedule(schedule), kWorkedExampleBytes)
      << "the bitstream changed: if that is deliberate, update spec/entropy-coding.md and the bitstream version";
  const Decoded decoded = decode_schedule(kWorkedExampleBytes, schedule);
  EXPECT_EQ(decoded.values, values_of(schedule));
  EXPECT_TRUE(decoded.status.ok()) << decoded.status.message();
}

TEST(RangeCoderSpec, WorkedExampleDecoderStatesMatchTheSpecification) {
  const std::vector<Symbol> schedule = worked_example();
  std::vector<reference::TraceStep> trace;
  reference::Decoder decoder(kWorkedExampleBytes.data(), kWorkedExampleBytes.size());
  EXPECT_EQ(decoder.code, 0x24846DC6u);
  decoder.trace = &trace;
  ReferenceModels models;
  struct State {
    uint32_t range, code;
    size_t pos;
  };
  std::vector<State> after_symbol;
  for (const Symbol& symbol : schedule) {
    EXPECT_EQ(reference_decode_symbol(decoder, models, symbol), symbol.value);
    after_symbol.push_back({decoder.range, decoder.code, decoder.pos});
  }
  EXPECT_TRUE(decoder.End());
  // (range, code, pos) after each symbol: the table "State after each symbol" of the specification.
  const State expected_after_symbol[] = {
      {0x7FFFFC00, 0x24846DC6, 4},  {0x41FFFBE0, 0x24846DC6, 4},  {0x1EF8401F, 0x017CB205, 4},
      {0x0FF042F0, 0x017CB205, 4},  {0x0871A7E8, 0x017CB205, 4},  {0x0498DC7C, 0x017CB205, 4},
      {0x029160A8, 0x017CB205, 4},  {0x01192F38, 0x00048095, 4},  {0x9BF43000, 0x0480950C, 5},
      {0x58A34948, 0x0480950C, 5},  {0x58A40000, 0x004D0C88, 6},  {0x01847800, 0x004D0C88, 6},
      {0x0335A000, 0x026F873A, 8},  {0x019AD000, 0x00E3FA13, 9},  {0x019A0000, 0x01556300, 12},
      {0x33400000, 0x21E30000, 13}, {0x0CD00000, 0x00F00000, 14},
  };
  // The first 17 DecodeBit calls: the table "Decoder steps" of the specification.
  const reference::TraceStep expected_steps[] = {
      {1024, 0xFFFFFFFF, 0x24846DC6, 0x7FFFFC00, 0, 1056, 0x7FFFFC00, 0x24846DC6, 4},
      {1056, 0x7FFFFC00, 0x24846DC6, 0x41FFFBE0, 0, 1087, 0x41FFFBE0, 0x24846DC6, 4},
      {1087, 0x41FFFBE0, 0x24846DC6, 0x2307BBC1, 1, 1054, 0x1EF8401F, 0x017CB205, 4},
      {1054, 0x1EF8401F, 0x017CB205, 0x0FF042F0, 0, 1085, 0x0FF042F0, 0x017CB205, 4},
      {1085, 0x0FF042F0, 0x017CB205, 0x0871A7E8, 0, 1115, 0x0871A7E8, 0x017CB205, 4},
      {1115, 0x0871A7E8, 0x017CB205, 0x0498DC7C, 0, 1144, 0x0498DC7C, 0x017CB205, 4},
      {1144, 0x0498DC7C, 0x017CB205, 0x029160A8, 0, 1172, 0x029160A8, 0x017CB205, 4},
      {1172, 0x029160A8, 0x017CB205, 0x01783170, 1, 1136, 0x01192F38, 0x00048095, 4},
      {1136, 0x01192F38, 0x00048095, 0x009BF430, 0, 1164, 0x9BF43000, 0x0480950C, 5},
      {1164, 0x9BF43000, 0x0480950C, 0x58A34948, 0, 1191, 0x58A34948, 0x0480950C, 5},
      {1024, 0x58A34948, 0x0480950C, 0x2C51A400, 0, 1056, 0x2C51A400, 0x0480950C, 5},
      {1024, 0x2C51A400, 0x0480950C, 0x1628D000, 0, 1056, 0x1628D000, 0x0480950C, 5},
      {1024, 0x1628D000, 0x0480950C, 0x0B146800, 0, 1056, 0x0B146800, 0x0480950C, 5},
      {1024, 0x0B146800, 0x0480950C, 0x058A3400, 0, 1056, 0x058A3400, 0x0480950C, 5},
      {1024, 0x058A3400, 0x0480950C, 0x02C51800, 1, 992, 0x02C51C00, 0x01BB7D0C, 5},
      {1024, 0x02C51C00, 0x01BB7D0C, 0x01628C00, 1, 992, 0x01629000, 0x0058F10C, 5},
      {1024, 0x01629000, 0x0058F10C, 0x00B14800, 0, 1056, 0xB1480000, 0x58F10C88, 6},
  };
  ASSERT_EQ(after_symbol.size(), std::size(expected_after_symbol));
  for (size_t i = 0; i < after_symbol.size(); ++i) {
    EXPECT_EQ(after_symbol[i].range, expected_after_symbol[i].range) << "symbol " << i;
    EXPECT_EQ(after_symbol[i].code, expected_after_symbol[i].code) << "symbol " << i;
    EXPECT_EQ(after_symbol[i].pos, expected_after_symbol[i].pos) << "symbol " << i;
  }
  ASSERT_GE(trace.size(), std::size(expected_steps));
  for (size_t i = 0; i < std::size(expected_steps); ++i) {
    const reference::TraceStep& actual = trace[i];
    const reference::TraceStep& expected = expected_steps[i];
    EXPECT_EQ(actual.prob, expected.prob) << "step " << i + 1;
    EXPECT_EQ(actual.range, expected.range) << "step " << i + 1;
    EXPECT_EQ(actual.code, expected.code) << "step " << i + 1;
    EXPECT_EQ(actual.bound, expected.bound) << "step " << i + 1;
    EXPECT_EQ(actual.bit, expected.bit) << "step " << i + 1;
    EXPECT_EQ(actual.prob_after, expected.prob_after) << "step " << i + 1;
    EXPECT_EQ(actual.range_after, expected.range_after) << "step " << i + 1;
    EXPECT_EQ(actual.code_after, expected.code_after) << "step " << i + 1;
    EXPECT_EQ(actual.pos_after, expected.pos_after) << "step " << i + 1;
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Compression.

double binary_entropy(double p) {
  return p <= 0 || p >= 1 ? 0.0 : -(p * std::log2(p) + (1 - p) * std::log2(1 - p));
}

// Bits per coded bit for `count` bits that are 1 with probability p_one; `empirical_entropy` receives the order-0
// entropy of the bits actually drawn, in bits per bit.
double bits_per_bit(double p_one, int count, double& empirical_entropy) {
  Random random(7);
  std::vector<uint8_t> bytes;
  RangeEncoder encoder(bytes);
  BitModel model;
  int ones = 0;
  for (int i = 0; i < count; ++i) {
    const uint32_t bit = random.bit_with_probability(p_one);
    ones += int(bit);
    encoder.encode_bit(model, bit);
  }
  encoder.finish();
  empirical_entropy = binary_entropy(double(ones) / count);
  return 8.0 * double(bytes.size()) / count;
}

TEST(RangeCoderCompression, LikelyBitCostsWellUnderHalfABit) {
  double entropy = 0;
  const double cost = bits_per_bit(0.05, 1000000, entropy);
  EXPECT_LT(cost, 0.31);  // entropy 0.286
}

TEST(RangeCoderCompression, BitCostIsNearTheEmpiricalEntropy) {
  // A shift-5 estimator pays about 1/(2 ln 2 (64 - 1)) = 0.011 bits per bit for its noise over a stationary source.
  for (double p_one : {0.5, 0.3, 0.1, 0.05}) {
    double entropy = 0;
    const double cost = bits_per_bit(p_one, 1000000, entropy);
    EXPECT_LT(cost, entropy * 1.05) << "p(1) = " << p_one;
    EXPECT_LT(cost, entropy + 0.013) << "p(1) = " << p_one;
    printf("p(1) %.2f: %.4f bits per bit, entropy %.4f (+%.1f%%)\n", p_one, cost, entropy, 100 * (cost / entropy - 1));
  }
}

// Two-sided geometric ("discrete Laplacian") integers with mean magnitude about `scale`.
std::vector<int32_t> laplacian_integers(Random& random, double scale, size_t count) {
  std::vector<int32_t> values;
  for (size_t i = 0; i < count; ++i) {
    const int32_t magnitude = int32_t(std::floor(-scale * std::log(1.0 - random.uniform())));
    values.push_back(random.below(2) ? magnitude : -magnitude);
  }
  return values;
}

TEST(RangeCoderCompression, LaplacianIntegersCostNearTheirEntropy) {
  for (double scale : {0.5, 4.0, 50.0, 3000.0}) {
    Random random(8);
    const std::vector<int32_t> values = laplacian_integers(random, scale, 200000);
    std::map<int32_t, size_t> histogram;
    for (int32_t value : values) ++histogram[value];
    double entropy_bits = 0;
    for (const auto& entry : histogram) {
      const double p = double(entry.second) / double(values.size());
      entropy_bits -= double(entry.second) * std::log2(p);
    }
    std::vector<uint8_t> bytes;
    RangeEncoder encoder(bytes);
    SignedModel model;
    for (int32_t value : values) model.encode(encoder, value);
    encoder.finish();
    const double cost = 8.0 * double(bytes.size()) / double(values.size());
    const double entropy = entropy_bits / double(values.size());
    printf("scale %.1f: %.4f bits per integer, entropy %.4f (+%.1f%%)\n", scale, cost, entropy,
           100 * (cost / entropy - 1));
    EXPECT_LT(cost, entropy * 1.08 + 0.03) << "scale " << scale;
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Hostile input.

TEST(RangeCoderHostile, EmptyInputIsTruncated) {
  RangeDecoder decoder(nullptr, 0);
  EXPECT_TRUE(decoder.overrun());
  EXPECT_FALSE(decoder.finish().ok());
}

TEST(RangeCoderHostile, EveryPrefixDecodesTheSameLeadingSymbolsOrFails) {
  int accepted = 0, overrun = 0, prefixes = 0;
  for (uint64_t seed = 300; seed < 310; ++seed) {
    Random random(seed);
    const std::vector<Symbol> schedule = random_schedule(random, 400);
    const std::vector<uint8_t> bytes = encode_schedule(schedule);
    for (size_t length = 0; length < bytes.size(); ++length) {
      const Decoded decoded = decode_schedule(bytes.data(), length, schedule);
      // A symbol decoded from bytes that are all present is the encoded one.
      for (size_t i = 0; i < schedule.size() && decoded.positions[i] <= length; ++i)
        ASSERT_EQ(decoded.values[i], schedule[i].value) << "seed " << seed << ", prefix " << length << ", symbol " << i;
      ++prefixes;
      if (decoded.overrun) {
        ++overrun;
        EXPECT_FALSE(decoded.status.ok());
      }
      if (decoded.status.ok()) ++accepted;
    }
  }
  // A prefix passes only when it happens to be the unique stream of some other symbols; it must be rare.
  printf("of %d prefixes: %d overrun, %d rejected otherwise, %d accepted\n", prefixes, overrun,
         prefixes - overrun - accepted, accepted);
  EXPECT_LT(accepted * 100, prefixes);
}

TEST(RangeCoderHostile, TrailingBytesAreRejected) {
  Random random(11);
  const std::vector<Symbol> schedule = random_schedule(random, 500);
  std::vector<uint8_t> bytes = encode_schedule(schedule);
  ASSERT_TRUE(decode_schedule(bytes, schedule).status.ok());
  for (uint8_t extra : {0x00, 0x01, 0xFF}) {
    std::vector<uint8_t> longer = bytes;
    longer.push_back(extra);
    const Decoded decoded = decode_schedule(longer, schedule);
    EXPECT_EQ(decoded.values, values_of(schedule));
    EXPECT_FALSE(decoded.status.ok());
    EXPECT_NE(decoded.status.message().find("trailing"), std::string::npos) << decoded.status.message();
  }
}

TEST(RangeCoderHostile, LengthClassAbove32IsAnError) {
  for (uint32_t length_class : {33u, 40u, 63u}) {
    // An UnsignedModel starts with a 6-bit tree of fresh contexts: a BitTreeModel(6) writes what it reads.
    std::vector<uint8_t> bytes;
    RangeEncoder encoder(bytes);
    BitTreeModel tree(kUnsignedClassBits);
    tree.encode(encoder, length_class);
    encoder.encode_direct_bits(0xFFFFFFFF, 32);
    encoder.finish();
    RangeDecoder decoder(bytes.data(), bytes.size());
    UnsignedModel model;
    EXPECT_EQ(model.decode(decoder), 0u);
    EXPECT_TRUE(decoder.failed());
    EXPECT_FALSE(decoder.finish().ok());
    EXPECT_NE(decoder.finish().message().find("32 bits"), std::string::npos);
  }
}

TEST(RangeCoderHostile, SignedMagnitudeOutsideInt32IsAnError) {
  // nonzero, sign, then |value| - 1 through a fresh UnsignedModel, as SignedModel lays them out.
  for (uint32_t negative : {0u, 1u}) {
    std::vector<uint8_t> bytes;
    RangeEncoder encoder(bytes);
    BitModel nonzero, sign;
    UnsignedModel magnitude;
    encoder.encode_bit(nonzero, 1);
    encoder.encode_bit(sign, negative);
    magnitude.encode(encoder, negative ? 0x80000000u : 0x7FFFFFFFu);  // |value| = 2^31 + 1 or 2^31
    encoder.finish();
    RangeDecoder decoder(bytes.data(), bytes.size());
    SignedModel model;
    EXPECT_EQ(model.decode(decoder), 0);
    EXPECT_FALSE(decoder.finish().ok());
    EXPECT_NE(decoder.finish().message().find("int32"), std::string::npos);
  }
}

// Garbage and damaged streams: no crash, no read out of bounds (under the sanitizer build), the same symbols and the
// same verdict as the specification's decoder, and a bounded amount of work (the schedule's length).
void expect_reference_agrees(const std::vector<uint8_t>& bytes, const std::vector<Symbol>& schedule, const char* what,
                             size_t index) {
  const Decoded decoded = decode_schedule(bytes, schedule);
  reference::Decoder decoder(bytes.data(), bytes.size());
  ReferenceModels models;
  std::vector<uint32_t> values;
  for (const Symbol& symbol : schedule) values.push_back(reference_decode_symbol(decoder, models, symbol));
  ASSERT_EQ(decoded.values, values) << what << " " << index;
  ASSERT_EQ(decoded.status.ok(), decoder.End()) << what << " " << index;
}

TEST(RangeCoderHostile, GarbageDecodesLikeTheSpecificationWithoutCrashing) {
  Random random(12);
  const std::vector<Symbol> schedule = random_schedule(random, 300);
  for (size_t i = 0; i < 3000; ++i) {
    std::vector<uint8_t> garbage(random.below(120));
    const uint32_t style = random.below(4);
    for (uint8_t& byte : garbage) byte = style == 0 ? 0x00 : style == 1 ? 0xFF : uint8_t(random.next32());
    expect_reference_agrees(garbage, schedule, "garbage", i);
  }
}

TEST(RangeCoderHostile, ByteFlipsDecodeLikeTheSpecificationWithoutCrashing) {
  Random random(13);
  const std::vector<Symbol> schedule = random_schedule(random, 1000);
  const std::vector<uint8_t> bytes = encode_schedule(schedule);
  int rejected = 0;
  for (size_t i = 0; i < 2000; ++i) {
    std::vector<uint8_t> damaged = bytes;
    damaged[random.below(uint32_t(damaged.size()))] ^= uint8_t(1u << random.below(8));
    expect_reference_agrees(damaged, schedule, "flip", i);
    if (!decode_schedule(damaged, schedule).status.ok()) ++rejected;
  }
  printf("%d of 2000 single-bit flips rejected by the range coder alone\n", rejected);
}

// ---------------------------------------------------------------------------------------------------------------
// Residual symbols (spec section 8; codec/common/residual_contexts.h).

// Residuals like a stream's: mostly 0 and ±1, some small, a few large, whole vertices at rest for stretches; the
// extremes of int32 (lossy) or of int64 (lossless, which escapes what does not fit int32).
std::vector<int64_t> random_residuals(Random& random, size_t welded_count, size_t frames, bool lossless) {
  std::vector<int64_t> r(frames * welded_count * 3);
  for (size_t i = 0; i < r.size(); i += 3) {
    if (random.below(3) == 0) continue;  // a vertex at rest
    for (size_t a = 0; a < 3; ++a) {
      const uint32_t kind = random.below(100);
      const int64_t magnitude = kind < 50   ? 0
                                : kind < 80 ? 1
                                : kind < 92 ? 2 + random.below(3)
                                : kind < 98 ? random.below(3000)
                                            : int64_t(random.any_magnitude() >> 1);  // up to 2^31 − 1
      r[i + a] = random.below(2) ? magnitude : -magnitude;
    }
  }
  const int64_t lossy_extremes[] = {INT32_MAX, -INT32_MAX, INT32_MAX - 1, 3, -3};
  const int64_t lossless_extremes[] = {INT32_MIN,
                                       INT64_MIN,
                                       INT64_MAX,
                                       int64_t(1) << 40,
                                       -(int64_t(1) << 33),
                                       int64_t(INT32_MAX) + 1,
                                       int64_t(INT32_MIN) - 1};
  for (int64_t value : lossy_extremes) r[random.below(uint32_t(r.size()))] = value;
  if (lossless)
    for (int64_t value : lossless_extremes) r[random.below(uint32_t(r.size()))] = value;
  return r;
}

std::vector<uint8_t> encode_residual_stream(const std::vector<int64_t>& residuals, size_t welded_count, bool lossless) {
  std::vector<uint8_t> bytes;
  RangeEncoder encoder(bytes);
  encode_residuals(encoder, residuals, welded_count, lossless);
  encoder.finish();
  return bytes;
}

struct DecodedResiduals {
  std::vector<int64_t> values;
  Status status;
};

// From an exactly sized heap copy, so that AddressSanitizer sees any read past the end.
DecodedResiduals decode_residual_stream(const std::vector<uint8_t>& bytes, size_t welded_count, size_t count,
                                        bool lossless) {
  const std::unique_ptr<uint8_t[]> copy(bytes.empty() ? nullptr : new uint8_t[bytes.size()]);
  std::copy(bytes.begin(), bytes.end(), copy.get());
  RangeDecoder decoder(copy.get(), bytes.size());
  DecodedResiduals decoded;
  decoded.status = decode_residuals(decoder, welded_count, count / (welded_count * 3), lossless, decoded.values);
  if (decoded.status.ok()) decoded.status = decoder.finish();
  return decoded;
}

std::vector<int64_t> reference_decode_residuals(const std::vector<uint8_t>& bytes, size_t welded_count, size_t count,
                                                bool lossless, bool& valid) {
  reference::Decoder decoder(bytes.data(), bytes.size());
  std::vector<int64_t> values(count, 0);
  reference::DecodeResidualSection(decoder, welded_count, lossless, values);
  valid = decoder.End();
  return values;
}

TEST(ResidualCoding, RoundTripsLossyAndLossless) {
  struct Shape {
    size_t welded_count, frames;
  };
  Random random(20);
  for (const Shape shape : {Shape{1, 1}, Shape{1, 300}, Shape{7, 50}, Shape{300, 6}, Shape{5000, 3}})
    for (bool lossless : {false, true}) {
      const std::vector<int64_t> residuals = random_residuals(random, shape.welded_count, shape.frames, lossless);
      const std::vector<uint8_t> bytes = encode_residual_stream(residuals, shape.welded_count, lossless);
      const DecodedResiduals decoded = decode_residual_stream(bytes, shape.welded_count, residuals.size(), lossless);
      EXPECT_EQ(decoded.values, residuals) << shape.welded_count << " × " << shape.frames << " lossless " << lossless;
      EXPECT_TRUE(decoded.status.ok()) << decoded.status.message();
      bool valid = false;
      EXPECT_EQ(reference_decode_residuals(bytes, shape.welded_count, residuals.size(), lossless, valid), residuals);
      EXPECT_TRUE(valid) << "the specification's decoder rejects a stream of " << shape.welded_count << " × "
                         << shape.frames << " lossless " << lossless;
    }
}

TEST(ResidualCoding, VerticesAtRestCostOneLikelyDecisionEach) {
  // 100 000 vertex-frames of zeros: the vertex bit's probability saturates at 2017/2048, 0.022 bits per vertex.
  const std::vector<int64_t> residuals(1000 * 100 * 3, 0);
  const std::vector<uint8_t> bytes = encode_residual_stream(residuals, 1000, false);
  EXPECT_LT(bytes.size(), 320u);
  EXPECT_EQ(decode_residual_stream(bytes, 1000, residuals.size(), false).values, residuals);
}

// The worked example of spec/entropy-coding.md section 10.2: four frames of two vertices.
// clang-format off
const std::vector<int64_t> kResidualExample = {
    0,                0,         0,  1, 0,  -1,  // frame 0: vertex 0, vertex 1
    0,                0,         2,  1, 0,  0,   // frame 1
    -3,               1000,      0,  0, -1, 0,   // frame 2
    int64_t(1) << 40, INT32_MIN, 5,  0, 0,  0,   // frame 3
};
// clang-format on
const std::vector<uint8_t> kResidualExampleBytes = {
    0x64, 0x2B, 0x06, 0xF6, 0xFA, 0x06, 0x8B, 0xD6, 0xB4, 0x19, 0x9F, 0xFF, 0xBA, 0x3D, 0x9C, 0x17, 0x40, 0xCC,
    0x00, 0x00, 0x16, 0x8C, 0x94, 0x3F, 0xFF, 0xD1, 0x89, 0x4F, 0xFF, 0xF4, 0x62, 0x54, 0x00, 0x10, 0x05};

TEST(RangeCoderSpec, ResidualWorkedExampleIsAGoldenVector) {
  EXPECT_EQ(encode_residual_stream(kResidualExample, 2, true), kResidualExampleBytes)
      << "the bitstream changed: if that is deliberate, update spec/entropy-coding.md and the bitstream version";
  const DecodedResiduals decoded = decode_residual_stream(kResidualExampleBytes, 2, kResidualExample.size(), true);
  EXPECT_EQ(decoded.values, kResidualExample);
  EXPECT_TRUE(decoded.status.ok()) << decoded.status.message();

  reference::Decoder decoder(kResidualExampleBytes.data(), kResidualExampleBytes.size());
  EXPECT_EQ(decoder.code, 0x642B06F6u);
  std::vector<int64_t> values(kResidualExample.size(), 0);
  std::vector<reference::DecoderState> after_vertex;
  reference::DecodeResidualSection(decoder, 2, true, values, &after_vertex);
  EXPECT_EQ(values, kResidualExample);
  EXPECT_TRUE(decoder.End());
  // (range, code, pos) after each vertex: the specification's table.
  const reference::DecoderState expected[] = {
      {0x7FFFFC00, 0x642B06F6, 4},  {0x7C000000, 0x430B16FA, 5},  {0x01C36000, 0x015997FA, 5},
      {0x0745EC00, 0x070FFA06, 6},  {0x0CCCC000, 0x09073419, 10}, {0x2E8C9C00, 0x2DD8399F, 11},
      {0x02E77000, 0x009A4000, 38}, {0x0173B800, 0x009A4000, 38},
  };
  ASSERT_EQ(after_vertex.size(), std::size(expected));
  for (size_t i = 0; i < after_vertex.size(); ++i) {
    EXPECT_EQ(after_vertex[i].range, expected[i].range) << "vertex-frame " << i;
    EXPECT_EQ(after_vertex[i].code, expected[i].code) << "vertex-frame " << i;
    EXPECT_EQ(after_vertex[i].pos, expected[i].pos) << "vertex-frame " << i;
  }
}

// The example above uses each context once or twice, so it cannot tell one context index from another; this one
// can: a longer lossy and a longer lossless stream, pinned by length and FNV-1a hash.
uint64_t fnv1a(const std::vector<uint8_t>& bytes) {
  uint64_t hash = 0xCBF29CE484222325ull;
  for (uint8_t byte : bytes) hash = (hash ^ byte) * 0x100000001B3ull;
  return hash;
}

TEST(RangeCoderSpec, ResidualStreamsOfRandomResidualsAreStable) {
  Random random(22);
  const std::vector<int64_t> lossy = random_residuals(random, 11, 60, false);
  const std::vector<int64_t> lossless = random_residuals(random, 11, 60, true);
  const std::vector<uint8_t> lossy_bytes = encode_residual_stream(lossy, 11, false);
  const std::vector<uint8_t> lossless_bytes = encode_residual_stream(lossless, 11, true);
  const char* changed = "the bitstream changed: if that is deliberate, update spec/entropy-coding.md and the version";
  EXPECT_EQ(lossy_bytes.size(), 699u) << changed;
  EXPECT_EQ(fnv1a(lossy_bytes), 1079544242202365237ull) << changed;
  EXPECT_EQ(lossless_bytes.size(), 738u) << changed;
  EXPECT_EQ(fnv1a(lossless_bytes), 15456904959548159823ull) << changed;
}

// One vertex, one frame, built decision by decision: every context is used once, so fresh BitModels stand in for
// the models of section 8.1. x is nonzero with the given sign and |x| − 3 = rest, optionally followed by 64 bits;
// y and z are 0.
std::vector<uint8_t> one_vertex_stream(uint32_t negative, uint32_t rest, const uint64_t* escaped_bits) {
  std::vector<uint8_t> bytes;
  RangeEncoder encoder(bytes);
  BitModel vertex, x_nonzero, x_negative, x_above_one, x_above_two, y_nonzero, z_nonzero;
  UnsignedModel magnitude;
  encoder.encode_bit(vertex, 1);
  encoder.encode_bit(x_nonzero, 1);
  encoder.encode_bit(x_negative, negative);
  encoder.encode_bit(x_above_one, 1);
  encoder.encode_bit(x_above_two, 1);
  magnitude.encode(encoder, rest);
  if (escaped_bits) {
    encoder.encode_direct_bits(uint32_t(*escaped_bits >> 32), 32);
    encoder.encode_direct_bits(uint32_t(*escaped_bits), 32);
  }
  encoder.encode_bit(y_nonzero, 0);
  encoder.encode_bit(z_nonzero, 0);
  encoder.finish();
  return bytes;
}

TEST(RangeCoderHostile, ResidualOneVertexStreamsAreBuiltRight) {
  // The hand-built streams of the tests below, with valid content, decode as intended.
  const uint64_t big = uint64_t(1) << 40;
  DecodedResiduals decoded = decode_residual_stream(one_vertex_stream(0, 4, nullptr), 1, 3, false);
  EXPECT_EQ(decoded.values, (std::vector<int64_t>{7, 0, 0}));
  EXPECT_TRUE(decoded.status.ok()) << decoded.status.message();
  decoded = decode_residual_stream(one_vertex_stream(1, 0x7FFFFFFD, &big), 1, 3, true);
  EXPECT_EQ(decoded.values, (std::vector<int64_t>{int64_t(big), 0, 0}));
  EXPECT_TRUE(decoded.status.ok()) << decoded.status.message();
}

TEST(RangeCoderHostile, ResidualEscapeInALossyStreamIsAnError) {
  const uint64_t big = uint64_t(1) << 40;
  const DecodedResiduals decoded = decode_residual_stream(one_vertex_stream(1, 0x7FFFFFFD, &big), 1, 3, false);
  EXPECT_FALSE(decoded.status.ok());
  EXPECT_NE(decoded.status.message().find("escape in a lossy stream"), std::string::npos) << decoded.status.message();
}

TEST(RangeCoderHostile, ResidualMagnitudeOutsideInt32IsAnError) {
  // +2^31 and −(2^31 + 1).
  for (uint32_t negative : {0u, 1u}) {
    const DecodedResiduals decoded =
        decode_residual_stream(one_vertex_stream(negative, negative ? 0x7FFFFFFEu : 0x7FFFFFFDu, nullptr), 1, 3, true);
    EXPECT_FALSE(decoded.status.ok()) << "negative " << negative;
    EXPECT_NE(decoded.status.message().find("outside int32"), std::string::npos) << decoded.status.message();
  }
}

TEST(RangeCoderHostile, ResidualEscapeOfAnInt32IsAnError) {
  // An escape must carry a value without a shorter code: INT32_MIN and values outside int32 only.
  for (int64_t value : {int64_t(0), int64_t(5), int64_t(INT32_MIN) + 1, int64_t(INT32_MAX)}) {
    const uint64_t bits = uint64_t(value);
    const DecodedResiduals decoded = decode_residual_stream(one_vertex_stream(1, 0x7FFFFFFD, &bits), 1, 3, true);
    EXPECT_FALSE(decoded.status.ok()) << value;
    EXPECT_NE(decoded.status.message().find("escape for a residual in int32"), std::string::npos)
        << decoded.status.message();
  }
}

// Garbage, damaged streams and every prefix: no crash, no read out of bounds (under the sanitizer build), and the
// specification's verdict; the same residuals whenever the stream is valid.
void expect_residual_reference_agrees(const std::vector<uint8_t>& bytes, size_t welded_count, size_t count,
                                      bool lossless, const char* what, size_t index) {
  const DecodedResiduals decoded = decode_residual_stream(bytes, welded_count, count, lossless);
  bool valid = false;
  const std::vector<int64_t> values = reference_decode_residuals(bytes, welded_count, count, lossless, valid);
  ASSERT_EQ(decoded.status.ok(), valid) << what << " " << index << ": " << decoded.status.message();
  if (valid) {
    ASSERT_EQ(decoded.values, values) << what << " " << index;
  }
}

TEST(RangeCoderHostile, ResidualGarbageFlipsAndPrefixesDecodeLikeTheSpecification) {
  Random random(21);
  for (bool lossless : {false, true}) {
    const size_t welded_count = 9, frames = 40;
    const std::vector<int64_t> residuals = random_residuals(random, welded_count, frames, lossless);
    const std::vector<uint8_t> bytes = encode_residual_stream(residuals, welded_count, lossless);
    for (size_t i = 0; i < 1000; ++i) {
      std::vector<uint8_t> garbage(random.below(400));
      const uint32_t style = random.below(4);
      for (uint8_t& byte : garbage) byte = style == 0 ? 0x00 : style == 1 ? 0xFF : uint8_t(random.next32());
      expect_residual_reference_agrees(garbage, welded_count, residuals.size(), lossless, "garbage", i);
    }
    int rejected = 0;
    for (size_t i = 0; i < 1000; ++i) {
      std::vector<uint8_t> damaged = bytes;
      damaged[random.below(uint32_t(damaged.size()))] ^= uint8_t(1u << random.below(8));
      expect_residual_reference_agrees(damaged, welded_count, residuals.size(), lossless, "flip", i);
      if (!decode_residual_stream(damaged, welded_count, residuals.size(), lossless).status.ok()) ++rejected;
    }
    EXPECT_GT(rejected, 950) << "lossless " << lossless;
    for (size_t length = 0; length < bytes.size(); ++length) {
      const std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + std::ptrdiff_t(length));
      expect_residual_reference_agrees(prefix, welded_count, residuals.size(), lossless, "prefix", length);
    }
  }
}

}  // namespace
}  // namespace segmorph
