#include "decode/track_decoder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "common/float_bits.h"
#include "common/range_coder.h"
#include "common/track_format.h"
#include "common/track_syntax.h"

namespace segmorph {

using namespace track_code;

namespace {

Status corrupt(const std::string& what) {
  return Status(StatusCode::bad_data, "track stream: " + what);
}

struct KeyDecoder {
  RangeDecoder& coder;
  void bit(BitModel& model, uint32_t& bit) { bit = coder.decode_bit(model); }
  void integer(SignedModel& model, int32_t& value) { value = model.decode(coder); }
  void check(bool ok, const char* reason) {
    if (!ok) coder.mark_invalid(reason);
  }
  bool failed() const { return coder.failed(); }
};

Status check_layout(const TrackLayout& layout) {
  for (size_t count : layout.time_counts)
    if (count == 0) return corrupt("the layout has an empty key-time array");
  for (const TrackLayout::Sampler& sampler : layout.samplers) {
    if (sampler.times < 0 || size_t(sampler.times) >= layout.time_counts.size())
      return corrupt("the layout names a key-time array it does not have");
    if (!components_fit(sampler.path, sampler.components)) return corrupt("the layout's component count is wrong");
  }
  return Status::Ok();
}

// The key times of one array of `count` keys.
void decode_times(RangeDecoder& decoder, Models& models, size_t count, std::vector<float>& times) {
  times.reserve(count);
  const uint32_t first = decoder.decode_direct_bits(32);
  if (first >= track_format::kInfinityBits) decoder.mark_invalid("key time is negative or not finite");
  times.push_back(bits_float(first));
  if (count == 1) return;
  const uint32_t last = decoder.decode_direct_bits(32);
  if (last >= track_format::kInfinityBits || last <= first) decoder.mark_invalid("key times are not increasing");
  const bool regular = count == 2 || decoder.decode_bit(models.regular);
  int64_t pattern = first, difference = 0;
  for (size_t k = 1; k + 1 < count && !decoder.failed(); ++k) {
    const int64_t previous = pattern;
    if (regular) {
      pattern = float_bits(regular_time(bits_float(first), bits_float(last), k, count));
    } else {
      difference += models.time_delta.decode(decoder);
      pattern += difference;
    }
    if (pattern <= previous || pattern >= last) decoder.mark_invalid("key times are not increasing");
    times.push_back(bits_float(uint32_t(std::clamp<int64_t>(pattern, 0, last))));
  }
  times.push_back(bits_float(last));
}

}  // namespace

Status decode_tracks(const uint8_t* data, size_t size, const TrackLayout& layout, TrackSet& out) {
  out = TrackSet();
  SEGMORPH_RETURN_IF_ERROR(check_layout(layout));
  if (size < track_format::kHeaderBytes || std::memcmp(data, track_format::kMagic, 4) != 0)
    return corrupt("not a segmorph track stream (bad magic)");
  if (data[4] != track_format::kVersion)
    return Status(StatusCode::unsupported, "track stream version " + std::to_string(data[4]) +
                                               " (this decoder reads version " +
                                               std::to_string(track_format::kVersion) + ")");
  RangeDecoder decoder(data + track_format::kHeaderBytes, size - track_format::kHeaderBytes);
  KeyDecoder keys{decoder};
  Models models;
  // A refusal names what disagrees, or what the range decoder found first (an invalid symbol, the end of the data).
  auto failed = [&](const std::string& what) {
    return decoder.failed() ? corrupt(decoder.finish().message()) : corrupt(what);
  };

  const uint32_t time_arrays = models.count.decode(decoder);
  if (decoder.failed() || time_arrays != layout.time_counts.size())
    return failed("it has " + std::to_string(time_arrays) + " key-time arrays, the file says " +
                  std::to_string(layout.time_counts.size()));
  out.times.resize(time_arrays);
  std::vector<std::vector<double>> times(time_arrays);
  for (size_t i = 0; i < time_arrays; ++i) {
    const uint32_t count = models.count.decode(decoder);
    if (decoder.failed() || count != layout.time_counts[i])
      return failed("key-time array " + std::to_string(i) + " has " + std::to_string(count) + " keys, the file says " +
                    std::to_string(layout.time_counts[i]));
    decode_times(decoder, models, count, out.times[i]);
    if (decoder.failed()) return failed("bad key times");
    times[i] = as_doubles(out.times[i]);
  }

  const uint32_t samplers = models.count.decode(decoder);
  if (decoder.failed() || samplers != layout.samplers.size())
    return failed("it has " + std::to_string(samplers) + " samplers, the file says " +
                  std::to_string(layout.samplers.size()));
  out.samplers.resize(samplers);
  for (size_t s = 0; s < samplers; ++s) {
    const TrackLayout::Sampler& expected = layout.samplers[s];
    TrackSampler& sampler = out.samplers[s];
    sampler.times = int(models.count.decode(decoder));
    sampler.path = TrackPath(decoder.decode_direct_bits(2));
    sampler.components = int(models.count.decode(decoder));
    const std::string which = "sampler " + std::to_string(s) + ": ";
    if (decoder.failed() || sampler.times != expected.times || sampler.path != expected.path ||
        sampler.components != expected.components)
      return failed(which + "its key-time array, path or component count is not what the file says");
    const uint32_t mantissa = decoder.decode_direct_bits(track_format::kStepMantissaBits);
    const int exponent = models.step_exponent.decode(decoder);
    if (decoder.failed() || exponent < track_format::kMinStepExponent || exponent > track_format::kMaxStepExponent)
      return failed(which + "bad quantization step");
    SamplerShape shape{sampler.path, size_t(sampler.components), grid_step(mantissa, exponent),
                       &times[size_t(sampler.times)], 1};
    if (shape.times->size() >= 3) shape.order = decoder.decode_bit(models.order) ? 2 : 1;
    std::vector<int32_t> q;
    code_keys(keys, models, shape, false, nullptr, q);
    if (decoder.failed()) return failed(which + "bad keys");
    dequantize(shape, q, sampler.values);
    for (float value : sampler.values)
      if (!std::isfinite(value)) return corrupt(which + "a value is not finite");
  }
  const Status status = decoder.finish();
  return status.ok() ? status : corrupt(status.message());
}

}  // namespace segmorph
