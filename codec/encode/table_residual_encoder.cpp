#include "encode/table_residual_encoder.h"

#include <algorithm>
#include <cassert>
#include <numeric>

#include "common/table_residual_format.h"

namespace segmorph {

using namespace table_code;

namespace {

int clamped(int64_t value) {
  return value < -2 ? -2 : value > 2 ? 2 : int(value);
}

// The symbol of a vertex's three residuals: 25 (x + 2) + 5 (y + 2) + (z + 2), each clamped to [−2, 2].
template <typename Symbol>
int symbol_of(const Symbol* r) {
  return (clamped(r[0]) + 2) * 25 + (clamped(r[1]) + 2) * 5 + clamped(r[2]) + 2;
}

// Frequencies summing to kTotal from symbol counts: every symbol seen gets at least 1, none more than kMaxFrequency;
// a context never used codes the zero symbol. Encoder only (the stream carries the result).
void normalize(const uint64_t* count, uint32_t* frequency) {
  uint64_t total = std::accumulate(count, count + kSymbols, uint64_t(0));
  std::vector<uint64_t> counts(count, count + kSymbols);
  if (total == 0) counts[kZeroSymbol] = total = 1;
  int64_t sum = 0;
  for (int s = 0; s < kSymbols; ++s) {
    frequency[s] = counts[s] == 0 ? 0 : uint32_t(std::max<uint64_t>(1, (counts[s] * kTotal + total / 2) / total));
    frequency[s] = std::min(frequency[s], kMaxFrequency);
    sum += frequency[s];
  }
  // The difference to kTotal from the most frequent symbols first, then (when every symbol seen is at the maximum)
  // to symbols not seen.
  std::vector<int> order(kSymbols);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return counts[a] > counts[b]; });
  int64_t difference = int64_t(kTotal) - sum;
  for (int s : order) {
    if (difference > 0) {
      const int64_t add = std::min<int64_t>(difference, int64_t(kMaxFrequency) - frequency[s]);
      frequency[s] += uint32_t(add), difference -= add;
    } else if (difference < 0 && frequency[s] > 1) {
      const int64_t take = std::min<int64_t>(-difference, int64_t(frequency[s]) - 1);
      frequency[s] -= uint32_t(take), difference += take;
    }
  }
  assert(difference == 0);
}

}  // namespace

template <typename Symbol>
void encode_table_residuals(RangeEncoder& body, const std::vector<Symbol>& residuals, size_t welded_count,
                            std::vector<uint8_t>& symbols) {
  const size_t count = residuals.size() / 3;  // vertex-frames
  assert(welded_count > 0 && residuals.size() % (welded_count * 3) == 0);
  std::vector<uint8_t> symbol(count), context(count);
  std::vector<uint8_t> history(welded_count, 0);
  std::vector<uint64_t> counts(kContexts * kSymbols, 0);
  for (size_t i = 0; i < count; ++i) {
    const Symbol* r = &residuals[i * 3];
    for (int a = 0; a < 3; ++a) assert(r[a] > INT32_MIN && r[a] <= INT32_MAX);
    uint8_t& h = history[i % welded_count];
    symbol[i] = uint8_t(symbol_of(r));
    context[i] = uint8_t(context_of(h));
    ++counts[context[i] * kSymbols + symbol[i]];
    h = next_history(h, kSymbolTable.symbol[symbol[i]].nonzero);
  }

  // The tables, then the excess magnitudes, into the body.
  std::vector<uint32_t> frequency(kContexts * kSymbols), start(kContexts * kSymbols);
  UnsignedModel table_model;
  for (int c = 0; c < kContexts; ++c) {
    normalize(&counts[c * kSymbols], &frequency[c * kSymbols]);
    uint32_t cumulative = 0;
    for (int s = 0; s < kSymbols; ++s) {
      table_model.encode(body, frequency[c * kSymbols + s]);
      start[c * kSymbols + s] = cumulative;
      cumulative += frequency[c * kSymbols + s];
    }
  }
  ExcessModels excess;
  for (size_t i = 0; i < count; ++i) {
    const uint8_t clamped_axes = kSymbolTable.symbol[symbol[i]].clamped;
    for (size_t a = 0; a < 3; ++a)
      if (clamped_axes & (1u << a)) {
        const int64_t value = residuals[i * 3 + a];
        const uint32_t magnitude = uint32_t(value < 0 ? -value : value);
        body.encode_bit(excess.above_two[a], magnitude > 2);
        if (magnitude > 2) excess.minus_three[a].encode(body, magnitude - 3);
      }
  }

  // rANS runs backwards: the last vertex-frame is coded first, so that the decoder reads forwards.
  uint32_t state[kStates] = {kStateLow, kStateLow};
  std::vector<uint16_t> reversed;
  for (size_t i = count; i-- > 0;) {
    uint32_t& x = state[i % kStates];
    const size_t at = context[i] * kSymbols + symbol[i];
    const uint32_t f = frequency[at];
    assert(f > 0);
    if (x >= (uint64_t(kStateLow >> kFrequencyBits) << 16) * f) {
      reversed.push_back(uint16_t(x));
      x >>= 16;
    }
    x = ((x / f) << kFrequencyBits) + x % f + start[at];
  }
  for (int k = kStates - 1; k >= 0; --k) {
    reversed.push_back(uint16_t(state[k]));
    reversed.push_back(uint16_t(state[k] >> 16));
  }
  for (size_t j = reversed.size(); j-- > 0;) {
    symbols.push_back(uint8_t(reversed[j]));
    symbols.push_back(uint8_t(reversed[j] >> 8));
  }
}

template void encode_table_residuals(RangeEncoder&, const std::vector<int64_t>&, size_t, std::vector<uint8_t>&);
template void encode_table_residuals(RangeEncoder&, const std::vector<int32_t>&, size_t, std::vector<uint8_t>&);

}  // namespace segmorph
