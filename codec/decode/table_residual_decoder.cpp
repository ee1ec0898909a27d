#include "decode/table_residual_decoder.h"

#include <cassert>
#include <utility>

namespace segmorph {

using namespace table_code;

namespace {

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
