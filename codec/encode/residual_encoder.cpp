#include "encode/residual_encoder.h"

#include <cassert>

#include "common/residual_contexts.h"

namespace segmorph {

using namespace residual_code;

namespace {

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

}  // namespace segmorph
