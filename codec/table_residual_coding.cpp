#include "table_residual_coding.h"

#include <algorithm>
#include <cassert>
#include <numeric>
#include <utility>

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

// What a symbol stands for: the clamped values, the axes that are nonzero (bit a for axis a) and the axes whose
// magnitude may be above 2 (clamped to ±2, an excess follows in the body).
struct SymbolValues {
  int8_t value[3];
  uint8_t nonzero;
  uint8_t clamped;
};

struct SymbolTable {
  SymbolValues symbol[kSymbols] = {};
};

constexpr SymbolTable make_symbol_table() {
  SymbolTable table;
  for (int s = 0; s < kSymbols; ++s) {
    SymbolValues& v = table.symbol[s];
    v.value[0] = int8_t(s / 25 - 2), v.value[1] = int8_t(s / 5 % 5 - 2), v.value[2] = int8_t(s % 5 - 2);
    for (int a = 0; a < 3; ++a) {
      v.nonzero = uint8_t(v.nonzero | (v.value[a] != 0) << a);
      v.clamped = uint8_t(v.clamped | (v.value[a] == 2 || v.value[a] == -2) << a);
    }
  }
  return table;
}
constexpr SymbolTable kSymbolTable = make_symbol_table();

// A vertex's history: its nonzero pattern one frame before (bits 0–2) and two frames before (bits 3–5).
uint32_t context_of(uint32_t history) {
  return (history & 7u) | uint32_t((history & 0x38u) != 0) << 3;
}
uint8_t next_history(uint32_t history, uint32_t nonzero) {
  return uint8_t(nonzero | (history & 7u) << 3);
}

// An entry of a context's decoding table, one per slot: the slot's symbol (bits 0–6), the symbol's frequency
// (bits 7–19) and the slot's offset from the symbol's first slot (bits 20–31).
uint32_t slot_entry(uint32_t symbol, uint32_t frequency, uint32_t offset) {
  return symbol | frequency << 7 | offset << 20;
}
uint32_t entry_symbol(uint32_t entry) {
  return entry & 0x7Fu;
}
uint32_t entry_frequency(uint32_t entry) {
  return (entry >> 7) & 0x1FFFu;
}
uint32_t entry_offset(uint32_t entry) {
  return entry >> 20;
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

// A magnitude above 2 on axis a, whose clamped value is `clamped` (±2). Rare: kept out of the inlined loop.
[[gnu::noinline]] int64_t decode_large(RangeDecoder& body, ExcessModels& models, size_t a, int64_t clamped) {
  const uint32_t rest = models.minus_three[a].decode(body);
  if (rest > uint32_t(INT32_MAX) - 3) {
    body.mark_invalid("animation stream: residual outside int32");
    return clamped;
  }
  const int64_t magnitude = 3 + int64_t(rest);
  return clamped < 0 ? -magnitude : magnitude;
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

TableResidualDecoder::TableResidualDecoder(size_t welded_count, const uint8_t* symbols, size_t symbol_bytes)
    : welded_count_(welded_count),
      words_(symbols),
      word_count_(symbol_bytes / 2),
      history_(welded_count, 0),
      clamped_(welded_count) {
  assert(symbol_bytes % 2 == 0 && symbol_bytes >= kMinSymbolBytes);
}

Status TableResidualDecoder::read_tables(RangeDecoder& body) {
  slots_.assign(size_t(kContexts) << kFrequencyBits, 0);
  UnsignedModel table_model;
  for (int c = 0; c < kContexts; ++c) {
    uint32_t cumulative = 0;
    for (uint32_t s = 0; s < kSymbols; ++s) {
      const uint32_t f = table_model.decode(body);
      if (body.failed()) return body.finish();
      if (f > kMaxFrequency || cumulative + f > kTotal)
        return Status(StatusCode::bad_data, "animation stream: bad residual frequency table");
      for (uint32_t slot = cumulative; slot < cumulative + f; ++slot)
        slots_[(size_t(c) << kFrequencyBits) + slot] = slot_entry(s, f, slot - cumulative);
      cumulative += f;
    }
    if (cumulative != kTotal) return Status(StatusCode::bad_data, "animation stream: bad residual frequency table");
  }
  // The states' initial words: high half first.
  for (int k = 0; k < kStates; ++k) {
    const uint32_t high = uint32_t(words_[4 * k]) | uint32_t(words_[4 * k + 1]) << 8;
    const uint32_t low = uint32_t(words_[4 * k + 2]) | uint32_t(words_[4 * k + 3]) << 8;
    state_[size_t(k)] = high << 16 | low;
    if (state_[size_t(k)] < kStateLow)
      return Status(StatusCode::bad_data, "animation stream: bad residual symbol state");
  }
  next_word_ = 2 * kStates;
  return Status::Ok();
}

void TableResidualDecoder::decode_frame(RangeDecoder& body, int64_t* r) {
  assert(!slots_.empty());
  // Members in locals: the stores below through uint8_t and int64_t pointers could otherwise alias them.
  const uint32_t* slots = slots_.data();
  uint8_t* history = history_.data();
  const uint8_t* words = words_;
  const size_t welded_count = welded_count_, word_count = word_count_;
  uint32_t x = state_[0], y = state_[1];
  size_t next = next_word_;
  // The vertices with a clamped axis (about one in seven at --error 0.15), listed without a branch and given their
  // magnitudes from the body after the loop, in the same order.
  uint32_t* clamped = clamped_.data();
  size_t clamped_count = 0;
  int64_t* const row = r;
  for (size_t w = 0; w < welded_count; ++w, r += 3) {
    const uint32_t h = history[w];
    const uint32_t entry = slots[context_of(h) << kFrequencyBits | (x & (kTotal - 1))];
    x = entry_frequency(entry) * (x >> kFrequencyBits) + entry_offset(entry);
    // Renormalization without a branch: whether a state needs a word is a coin toss to the branch predictor. Past
    // the last word the words read as 0 and `next` still counts them (checked after the frame).
    const uint32_t word = next < word_count ? uint32_t(words[2 * next]) | uint32_t(words[2 * next + 1]) << 8 : 0u;
    const bool refill = x < kStateLow;
    x = refill ? x << 16 | word : x;
    next += refill;
    std::swap(x, y);
    const SymbolValues& v = kSymbolTable.symbol[entry_symbol(entry)];
    r[0] = v.value[0], r[1] = v.value[1], r[2] = v.value[2];
    history[w] = next_history(h, v.nonzero);
    clamped[clamped_count] = uint32_t(w);
    clamped_count += v.clamped != 0;
  }
  for (size_t i = 0; i < clamped_count; ++i) {
    int64_t* residual = &row[size_t(clamped[i]) * 3];
    for (size_t a = 0; a < 3; ++a)
      if ((residual[a] == 2 || residual[a] == -2) && body.decode_bit(excess_.above_two[a]))
        residual[a] = decode_large(body, excess_, a, residual[a]);
  }
  state_[0] = x, state_[1] = y;
  next_word_ = next;
  if (next_word_ > word_count_) failure_ = "animation stream: the residual symbols are truncated";
}

void TableResidualDecoder::restore(const Position& position) {
  assert(position.history.size() == history_.size());
  next_word_ = position.next_word;
  state_ = position.state;
  history_ = position.history;
  excess_ = position.excess;
  failure_ = position.failure;
}

Status TableResidualDecoder::finish() const {
  if (failure_) return Status(StatusCode::bad_data, failure_);
  if (next_word_ != word_count_ || state_[0] != kStateLow || state_[1] != kStateLow)
    return Status(StatusCode::bad_data, "animation stream: the residual symbols do not end with the stream");
  return Status::Ok();
}

}  // namespace segmorph
