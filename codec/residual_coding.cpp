#include "residual_coding.h"

#include <array>
#include <cassert>

namespace segmorph {

// The models of one axis (spec section 8.1).
struct AxisModels {
  std::array<BitModel, 36> nonzero;
  std::array<BitModel, 9> negative;
  std::array<BitModel, 9> above_one;  // |r| > 1, given r ≠ 0
  std::array<BitModel, 9> above_two;  // |r| > 2, given |r| > 1
  UnsignedModel magnitude_minus_three;
};

struct ResidualModels {
  std::array<BitModel, 64> vertex;  // some residual of the vertex is nonzero
  std::array<AxisModels, 3> axis;
};

namespace {

constexpr int64_t kEscape = INT32_MIN;  // lossless only: the residual follows as 64 direct bits

// What the contexts of a residual use of the residuals p1, p2, p3 at the same vertex and axis one, two and three
// frames earlier (0 before the first frame), packed in a byte that is updated as each frame is coded, so that a
// symbol's contexts cost one byte load instead of three 8-byte loads a row apart (measured on cow at --error 0.15:
// read_stream takes 23 ms with the byte, 35 ms reading the three frames):
//   bits 0-1: q(p1) = min(|p1|, 2)    bit 2: p1 < 0
//   bits 3-4: q(p2)                   bit 5: p2 < 0
//   bit 6:    p3 ≠ 0
using History = uint8_t;

// The history with p1 moved to p2 and p2 to p3, p1 still 0: the history after a zero residual.
History aged_history(History h) {
  return History((h & 7u) << 3 | uint32_t((h & 0x18u) != 0) << 6);
}

History next_history(History h, int64_t value) {
  const uint32_t q = value == 0 ? 0u : (value == 1 || value == -1) ? 1u : 2u;
  return History(aged_history(h) | q | uint32_t(value < 0) << 2);
}

// The context indices of spec/entropy-coding.md section 8.2 as functions of the history byte.
struct ContextTables {
  uint8_t nonzero[128] = {};    // 2 · (2 · (3 q(p1) + q(p2)) + [p3 ≠ 0]); the caller adds the "earlier axis" bit
  uint8_t negative[128] = {};   // 3 t(p1) + t(p2), t = 0 for zero, 1 for positive, 2 for negative
  uint8_t magnitude[128] = {};  // 3 q(p1) + q(p2)
  uint8_t vertex[128] = {};     // this axis's share of the vertex context: 16 [p1 ≠ 0] + 4 [p2 ≠ 0] + [p3 ≠ 0]
};

constexpr ContextTables make_context_tables() {
  ContextTables tables;
  for (uint32_t h = 0; h < 128; ++h) {
    const uint32_t q1 = h & 3u, q2 = (h >> 3) & 3u, nonzero3 = h >> 6;
    if (q1 > 2 || q2 > 2) continue;  // not a history next_history() makes
    const uint32_t t1 = q1 == 0 ? 0 : 1 + ((h >> 2) & 1u), t2 = q2 == 0 ? 0 : 1 + ((h >> 5) & 1u);
    tables.nonzero[h] = uint8_t(2 * (2 * (3 * q1 + q2) + nonzero3));
    tables.negative[h] = uint8_t(3 * t1 + t2);
    tables.magnitude[h] = uint8_t(3 * q1 + q2);
    tables.vertex[h] = uint8_t(16 * (q1 != 0) + 4 * (q2 != 0) + nonzero3);
  }
  return tables;
}
constexpr ContextTables kContexts = make_context_tables();

// n1 · 16 + n2 · 4 + n3, nk the number of the vertex's three residuals k frames earlier that are nonzero.
size_t vertex_context(const History* h) {
  return size_t(kContexts.vertex[h[0]]) + kContexts.vertex[h[1]] + kContexts.vertex[h[2]];
}

// One symbol in [INT32_MIN, INT32_MAX]. `earlier`: an earlier axis of this vertex and frame is nonzero (0 or 1);
// `implied_nonzero`: the symbol is known to be nonzero, its flag is not coded.
void encode_symbol(RangeEncoder& encoder, AxisModels& models, History h, uint32_t earlier, bool implied_nonzero,
                   int32_t symbol) {
  assert(!implied_nonzero || symbol != 0);
  if (!implied_nonzero) encoder.encode_bit(models.nonzero[kContexts.nonzero[h] + earlier], symbol != 0);
  if (symbol == 0) return;
  encoder.encode_bit(models.negative[kContexts.negative[h]], symbol < 0);
  const uint32_t magnitude = symbol < 0 ? 0u - uint32_t(symbol) : uint32_t(symbol);  // 2^31 for INT32_MIN
  const size_t context = kContexts.magnitude[h];
  encoder.encode_bit(models.above_one[context], magnitude > 1);
  if (magnitude == 1) return;
  encoder.encode_bit(models.above_two[context], magnitude > 2);
  if (magnitude == 2) return;
  models.magnitude_minus_three.encode(encoder, magnitude - 3);
}

// After an escape symbol: the residual's 64 bits. Only lossless streams have escapes, and only for residuals that
// have no other code (outside (INT32_MIN, INT32_MAX]), so that each residual sequence has one stream.
int64_t decode_escaped(RangeDecoder& decoder, bool lossless) {
  if (!lossless) {
    decoder.mark_invalid("animation stream: escape in a lossy stream");
    return 0;
  }
  const uint64_t high = decoder.decode_direct_bits(32), low = decoder.decode_direct_bits(32);
  const int64_t value = int64_t((high << 32) | low);
  if (value > kEscape && value <= INT32_MAX) decoder.mark_invalid("animation stream: escape for a residual in int32");
  return value;
}

// Magnitudes of 3 and more, and escapes, rare in lossy streams: kept out of the inlined path. int32 holds magnitudes
// up to 2^31 − 1 for positive values and 2^31 for negative ones.
[[gnu::noinline]] int64_t decode_large(RangeDecoder& decoder, AxisModels& models, uint32_t negative, bool lossless) {
  const uint32_t rest = models.magnitude_minus_three.decode(decoder);
  if (rest > (negative ? 0x80000000u : 0x7FFFFFFFu) - 3) {
    decoder.mark_invalid("range-coded residual is outside int32");
    return negative ? -3 : 3;
  }
  const int64_t value = negative ? -int64_t(rest + 3) : int64_t(rest + 3);
  return value == kEscape ? decode_escaped(decoder, lossless) : value;
}

struct DecodedSymbol {
  int64_t value;
  History history;  // the history after it
};

// Mirrors encode_symbol, escape included. Inlined into the decoding loop: the decoder's time goes into these few
// decisions.
inline DecodedSymbol decode_symbol(RangeDecoder& decoder, AxisModels& models, History h, uint32_t earlier,
                                   bool implied_nonzero, bool lossless) {
  const History aged = aged_history(h);
  if (!implied_nonzero && decoder.decode_bit(models.nonzero[kContexts.nonzero[h] + earlier]) == 0) return {0, aged};
  const uint32_t negative = decoder.decode_bit_as_data(models.negative[kContexts.negative[h]]);
  const size_t context = kContexts.magnitude[h];
  const History signed_aged = History(aged | negative << 2);
  if (decoder.decode_bit(models.above_one[context]) == 0) return {negative ? -1 : 1, History(signed_aged | 1)};
  if (decoder.decode_bit(models.above_two[context]) == 0) return {negative ? -2 : 2, History(signed_aged | 2)};
  const int64_t value = decode_large(decoder, models, negative, lossless);
  return {value, next_history(h, value)};
}

}  // namespace

template <typename Symbol>
void encode_residuals(RangeEncoder& encoder, const std::vector<Symbol>& residuals, size_t welded_count,
                      [[maybe_unused]] bool lossless) {
  const size_t row = welded_count * 3;
  assert(row > 0 && residuals.size() % row == 0);
  ResidualModels models;
  std::vector<History> history(row, 0);
  for (size_t frame = 0; frame < residuals.size() / row; ++frame) {
    for (size_t w = 0; w < welded_count; ++w) {
      const Symbol* r = &residuals[frame * row + w * 3];
      History* h = &history[w * 3];
      const bool any = r[0] != 0 || r[1] != 0 || r[2] != 0;
      encoder.encode_bit(models.vertex[vertex_context(h)], any);
      for (size_t axis = 0; any && axis < 3; ++axis) {
        const bool earlier = (axis >= 1 && r[0] != 0) || (axis == 2 && r[1] != 0);
        const bool in_int32 = r[axis] > kEscape && r[axis] <= INT32_MAX;
        assert(lossless || in_int32);
        encode_symbol(encoder, models.axis[axis], h[axis], earlier, axis == 2 && !earlier,
                      in_int32 ? int32_t(r[axis]) : INT32_MIN);
        if (!in_int32) {
          const uint64_t bits = uint64_t(int64_t(r[axis]));
          encoder.encode_direct_bits(uint32_t(bits >> 32), 32);
          encoder.encode_direct_bits(uint32_t(bits), 32);
        }
      }
      for (size_t axis = 0; axis < 3; ++axis) h[axis] = next_history(h[axis], r[axis]);
    }
  }
}

template void encode_residuals(RangeEncoder&, const std::vector<int64_t>&, size_t, bool);
template void encode_residuals(RangeEncoder&, const std::vector<int32_t>&, size_t, bool);

ResidualDecoder::ResidualDecoder(size_t welded_count, bool lossless)
    : welded_count_(welded_count),
      lossless_(lossless),
      models_(std::make_unique<ResidualModels>()),
      history_(welded_count * 3, 0) {}

ResidualDecoder::ResidualDecoder(const ResidualDecoder& other)
    : welded_count_(other.welded_count_),
      lossless_(other.lossless_),
      models_(std::make_unique<ResidualModels>(*other.models_)),
      history_(other.history_) {}

ResidualDecoder::~ResidualDecoder() = default;

size_t ResidualDecoder::state_bytes() const {
  return sizeof(ResidualDecoder) + sizeof(ResidualModels) + history_.size();
}

void ResidualDecoder::decode_frame(RangeDecoder& decoder, int64_t* r) {
  ResidualModels& models = *models_;
  History* h = history_.data();
  for (size_t w = 0; w < welded_count_; ++w, r += 3, h += 3) {
    if (decoder.decode_bit(models.vertex[vertex_context(h)]) == 0) {
      r[0] = r[1] = r[2] = 0;
      h[0] = aged_history(h[0]), h[1] = aged_history(h[1]), h[2] = aged_history(h[2]);
      continue;
    }
    const DecodedSymbol x = decode_symbol(decoder, models.axis[0], h[0], 0, false, lossless_);
    const uint32_t x_nonzero = x.value != 0;
    const DecodedSymbol y = decode_symbol(decoder, models.axis[1], h[1], x_nonzero, false, lossless_);
    const uint32_t earlier = x_nonzero | uint32_t(y.value != 0);
    const DecodedSymbol z = decode_symbol(decoder, models.axis[2], h[2], earlier, !earlier, lossless_);
    r[0] = x.value, r[1] = y.value, r[2] = z.value;
    h[0] = x.history, h[1] = y.history, h[2] = z.history;
  }
}

Status decode_residuals(RangeDecoder& decoder, size_t welded_count, size_t frame_count, bool lossless,
                        std::vector<int64_t>& residuals) {
  const size_t row = welded_count * 3;
  assert(row > 0);
  ResidualDecoder frames(welded_count, lossless);
  residuals.clear();
  for (size_t frame = 0; frame < frame_count; ++frame) {
    residuals.resize((frame + 1) * row);
    frames.decode_frame(decoder, &residuals[frame * row]);
    // Garbage decodes as fast as a stream: stop at the first sign of it.
    if (decoder.failed()) return decoder.finish();
  }
  return Status::Ok();
}

}  // namespace segmorph
