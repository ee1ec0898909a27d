#include "decode/residual_decoder.h"

#include <cassert>

#include "common/residual_contexts.h"

namespace segmorph {

using namespace residual_code;

namespace {

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
