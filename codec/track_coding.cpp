#include "track_coding.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstring>
#include <string>

#include "float_bits.h"
#include "range_coder.h"
#include "track_coding_internal.h"
#include "track_format.h"

namespace segmorph {
namespace {

using track_format::kMaxQuantized;

constexpr int kPaths = 4;
constexpr int kSlots = 4;    // components with models of their own; weights 3, 4, … share the last
constexpr int kBuckets = 4;  // classes of the previous residual's magnitude: 0, 1, 2–3, ≥ 4

// The adaptive contexts of a stream, in one place so that encoder and decoder cannot disagree (spec/tracks.md,
// section 4). One instance serves the whole stream: samplers of one path share their residual statistics.
struct Models {
  UnsignedModel count;        // counts, time array indices, component counts
  BitModel regular;           // a time array of 3 keys or more is evenly spaced
  SignedModel time_delta;     // irregular times: second differences of the bit patterns
  SignedModel step_exponent;  // e of each sampler's step
  BitModel order;             // a sampler of 3 keys or more predicts by order 2
  BitModel escape;            // a rotation key codes all four components
  std::array<std::array<SignedModel, kSlots>, kPaths> first_key;
  std::array<std::array<std::array<SignedModel, kBuckets>, kSlots>, kPaths> residual;
};

Status corrupt(const std::string& what) {
  return Status(StatusCode::bad_data, "track stream: " + what);
}
Status unusable(const std::string& what) {
  return Status(StatusCode::invalid_argument, "tracks: " + what);
}

bool components_fit(TrackPath path, int components) {
  switch (path) {
    case TrackPath::translation:
    case TrackPath::scale:
      return components == 3;
    case TrackPath::rotation:
      return components == 4;
    case TrackPath::weights:
      return components >= 1;
  }
  return false;
}

int slot(size_t component) {
  return int(std::min(component, size_t(kSlots - 1)));
}

int bucket(int64_t residual) {
  const uint64_t magnitude = residual < 0 ? uint64_t(-residual) : uint64_t(residual);
  return magnitude == 0 ? 0 : magnitude == 1 ? 1 : magnitude <= 3 ? 2 : 3;
}

// (8 + m) · 2^(e − 3), exact in binary64.
double grid_step(uint32_t mantissa, int exponent) {
  return std::ldexp(double(8 + mantissa), exponent - 3);
}

int64_t clamp_quantized(int64_t value) {
  return std::clamp(value, -kMaxQuantized, kMaxQuantized);
}

// The nearest integer, halves away from zero, of x clamped to ±2^31 (beyond which every use clamps anyway; the clamp
// also keeps llround defined when x is infinite).
int64_t round_clamped(double x) {
  return std::llround(std::clamp(x, -2147483648.0, 2147483648.0));
}

// Regular times: key k of `count` keys from first to last, in binary64 in this order, rounded to binary32.
float regular_time(double first, double last, size_t k, size_t count) {
  return float(first + (double(k) * (last - first)) / double(count - 1));
}

// One sampler as its keys are coded.
struct SamplerShape {
  TrackPath path = TrackPath::translation;
  size_t components = 0;
  double step = 0;
  const std::vector<double>* times = nullptr;  // its decoded key times
  int order = 1;                               // prediction of keys 2, 3, …: 1 the previous key, 2 linear
};

int64_t identity(const SamplerShape& shape, size_t component) {
  const bool one = shape.path == TrackPath::scale || (shape.path == TrackPath::rotation && component == 3);
  return one ? clamp_quantized(round_clamped(1.0 / shape.step)) : 0;
}

// The prediction of component c of key k from the decoded keys before it (q: keys × components).
int64_t predict(const SamplerShape& shape, const std::vector<int32_t>& q, size_t k, size_t c) {
  if (k == 0) return identity(shape, c);
  const int64_t q1 = q[(k - 1) * shape.components + c];
  if (k == 1 || shape.order == 1) return q1;
  const int64_t q0 = q[(k - 2) * shape.components + c];
  const std::vector<double>& t = *shape.times;
  const double extrapolated = (double(q1 - q0) * (t[k] - t[k - 1])) / (t[k - 1] - t[k - 2]);
  return clamp_quantized(q1 + round_clamped(extrapolated));
}

// The rotation component to rebuild: the largest predicted magnitude, the first of equals.
size_t largest(const int64_t* prediction) {
  size_t m = 0;
  for (size_t c = 1; c < 4; ++c)
    if (std::llabs(prediction[c]) > std::llabs(prediction[m])) m = c;
  return m;
}

// Component m of a unit quaternion from the other three (q: the key's 4 quantized components), with the sign of
// its prediction.
int64_t rebuild(const int32_t* q, size_t m, int64_t prediction, double step) {
  double sum = 0.0;
  for (size_t c = 0; c < 4; ++c)
    if (c != m) {
      const double x = double(q[c]) * step;
      sum = sum + x * x;
    }
  const int64_t magnitude = clamp_quantized(round_clamped(std::sqrt(std::max(0.0, 1.0 - sum)) / step));
  return prediction < 0 ? -magnitude : magnitude;
}

// Encoder and decoder walk the keys with one function, code_keys, so that they cannot disagree on an order, a
// model or a prediction: KeyEncoder codes the symbol it is given, KeyDecoder overwrites it with the one it reads.
struct KeyEncoder {
  RangeEncoder& coder;
  void bit(BitModel& model, uint32_t& bit) { coder.encode_bit(model, bit); }
  void integer(SignedModel& model, int32_t& value) { model.encode(coder, value); }
  void check(bool ok, const char*) {
    assert(ok);  // the encoder's values are in range by construction
    (void)ok;
  }
  bool failed() const { return false; }
};

struct KeyDecoder {
  RangeDecoder& coder;
  void bit(BitModel& model, uint32_t& bit) { bit = coder.decode_bit(model); }
  void integer(SignedModel& model, int32_t& value) { value = model.decode(coder); }
  void check(bool ok, const char* reason) {
    if (!ok) coder.mark_invalid(reason);
  }
  bool failed() const { return coder.failed(); }
};

// Codes the keys of one sampler. Encoding: `target` holds the quantized values (keys × components) and `q`
// receives what the decoder will reconstruct: the same, except rebuilt rotation components (within
// kMaxRebuildError of the target). Decoding: `target` is null and `q` receives the decoded values.
template <class Coder>
void code_keys(Coder& coder, Models& models, const SamplerShape& shape, bool all_components, const int32_t* target,
               std::vector<int32_t>& q) {
  const size_t components = shape.components, keys = shape.times->size();
  const int path = int(shape.path);
  const bool rotation = shape.path == TrackPath::rotation;
  q.assign(keys * components, 0);
  std::vector<int64_t> prediction(components), previous_residual(components, 0);
  for (size_t k = 0; k < keys && !coder.failed(); ++k) {
    int32_t* key = &q[k * components];
    for (size_t c = 0; c < components; ++c) prediction[c] = predict(shape, q, k, c);
    size_t rebuilt = components;  // none
    if (rotation && k > 0) {
      const size_t m = largest(prediction.data());
      uint32_t escape = 1;
      if (target) {
        std::copy(target + k * 4, target + k * 4 + 4, key);
        const int64_t value = rebuild(key, m, prediction[m], shape.step);
        key[m] = int32_t(value);
        const bool zero = key[0] == 0 && key[1] == 0 && key[2] == 0 && key[3] == 0;
        escape = all_components || zero || std::llabs(value - target[k * 4 + m]) > track_format::kMaxRebuildError;
      }
      coder.bit(models.escape, escape);
      if (!escape) rebuilt = m;
    }
    for (size_t c = 0; c < components; ++c) {
      if (c == rebuilt) continue;
      int32_t residual = target ? int32_t(target[k * components + c] - prediction[c]) : 0;
      coder.integer(
          k == 0 ? models.first_key[path][slot(c)] : models.residual[path][slot(c)][bucket(previous_residual[c])],
          residual);
      const int64_t value = prediction[c] + residual;
      coder.check(value >= -kMaxQuantized && value <= kMaxQuantized, "track value out of range");
      key[c] = int32_t(clamp_quantized(value));
    }
    if (rebuilt < components) key[rebuilt] = int32_t(rebuild(key, rebuilt, prediction[rebuilt], shape.step));
    if (rotation) coder.check(key[0] != 0 || key[1] != 0 || key[2] != 0 || key[3] != 0, "rotation key is zero");
    if (k > 0)
      for (size_t c = 0; c < components; ++c) previous_residual[c] = key[c] - prediction[c];
  }
}

// The values of one sampler from its quantized keys; rotations are normalised.
void dequantize(const SamplerShape& shape, const std::vector<int32_t>& q, std::vector<float>& values) {
  values.resize(q.size());
  if (shape.path != TrackPath::rotation) {
    for (size_t i = 0; i < q.size(); ++i) values[i] = float(double(q[i]) * shape.step);
    return;
  }
  for (size_t k = 0; k < q.size(); k += 4) {
    double x[4];
    for (size_t c = 0; c < 4; ++c) x[c] = double(q[k + c]) * shape.step;
    const double norm = std::sqrt(((x[0] * x[0] + x[1] * x[1]) + x[2] * x[2]) + x[3] * x[3]);
    for (size_t c = 0; c < 4; ++c) values[k + c] = float(x[c] / norm);
  }
}

// ---- Encoder ----

Status check_times(const std::vector<float>& times) {
  if (times.empty()) return unusable("a key-time array is empty");
  if (times.size() > UINT32_MAX) return unusable("a key-time array has too many keys");
  for (size_t k = 0; k < times.size(); ++k) {
    if (float_bits(times[k]) >= track_format::kInfinityBits)
      return unusable("key time " + std::to_string(times[k]) + " is negative, -0 or not finite");
    if (k > 0 && !(times[k] > times[k - 1])) return unusable("key times are not strictly increasing");
  }
  return Status::Ok();
}

struct SamplerPlan {
  uint32_t mantissa = 0;
  int exponent = 0;
  std::vector<int32_t> quantized;  // keys × components; rotations made sign-continuous
};

// The largest step of the grid not above `step`.
Status plan_step(double step, SamplerPlan& plan) {
  if (!std::isfinite(step) || !(step > 0)) return unusable("quantization steps must be finite and positive");
  int binary_exponent;  // step = fraction · 2^binary_exponent, fraction in [0.5, 1)
  const double fraction = std::frexp(step, &binary_exponent);
  plan.exponent = binary_exponent - 1;
  plan.mantissa = uint32_t(std::floor(fraction * 16.0)) - 8;
  if (plan.exponent < track_format::kMinStepExponent || plan.exponent > track_format::kMaxStepExponent)
    return unusable("quantization step " + std::to_string(step) + " outside [2^-40, 2^21)");
  return Status::Ok();
}

// glTF interpolates rotations along the shorter arc (glTF 2.0, Appendix C), so q and −q play the same: each key
// takes the sign nearer its predecessor, the first key the sign nearer the identity (w ≥ 0), which keeps the track
// smooth for prediction and its first key near the identity prediction.
std::vector<float> sign_continuous(const std::vector<float>& values) {
  std::vector<float> out = values;
  const float identity[4] = {0, 0, 0, 1};
  for (size_t k = 0; k < out.size(); k += 4) {
    const float* previous = k == 0 ? identity : &out[k - 4];
    double dot = 0;
    for (size_t c = 0; c < 4; ++c) dot += double(out[k + c]) * double(previous[c]);
    if (dot < 0)
      for (size_t c = 0; c < 4; ++c) out[k + c] = -out[k + c];
  }
  return out;
}

Status plan_sampler(const TrackSampler& sampler, double requested_step, SamplerPlan& plan) {
  SEGMORPH_RETURN_IF_ERROR(plan_step(requested_step, plan));
  const double step = grid_step(plan.mantissa, plan.exponent);
  const bool rotation = sampler.path == TrackPath::rotation;
  const std::vector<float> values = rotation ? sign_continuous(sampler.values) : sampler.values;
  plan.quantized.resize(values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    const double x = double(values[i]) / step;
    if (!(std::fabs(x) < double(kMaxQuantized)))  // NaN fails too
      return unusable("value " + std::to_string(values[i]) + " is not finite or too large for its step");
    plan.quantized[i] = int32_t(std::llround(x));
  }
  if (rotation)
    for (size_t k = 0; k < values.size(); k += 4)
      if (plan.quantized[k] == 0 && plan.quantized[k + 1] == 0 && plan.quantized[k + 2] == 0 &&
          plan.quantized[k + 3] == 0)
        return unusable("a rotation key quantizes to zero");
  return Status::Ok();
}

Status check_tracks(const TrackSet& tracks, const std::vector<double>& steps) {
  if (steps.size() != tracks.samplers.size()) return unusable("one step per sampler");
  if (tracks.times.size() > UINT32_MAX || tracks.samplers.size() > UINT32_MAX) return unusable("too many tracks");
  for (const std::vector<float>& times : tracks.times) SEGMORPH_RETURN_IF_ERROR(check_times(times));
  for (const TrackSampler& sampler : tracks.samplers) {
    if (sampler.times < 0 || size_t(sampler.times) >= tracks.times.size())
      return unusable("a sampler names no key-time array");
    if (!components_fit(sampler.path, sampler.components)) return unusable("a sampler's component count is wrong");
    if (sampler.values.size() != tracks.times[size_t(sampler.times)].size() * size_t(sampler.components))
      return unusable("a sampler's value count is not keys × components");
  }
  return Status::Ok();
}

void encode_times(RangeEncoder& encoder, Models& models, const std::vector<float>& times) {
  const size_t count = times.size();
  models.count.encode(encoder, uint32_t(count));
  encoder.encode_direct_bits(float_bits(times[0]), 32);
  if (count == 1) return;
  encoder.encode_direct_bits(float_bits(times[count - 1]), 32);
  if (count == 2) return;
  bool regular = true;
  for (size_t k = 1; k + 1 < count && regular; ++k)
    regular = float_bits(regular_time(times[0], times[count - 1], k, count)) == float_bits(times[k]);
  encoder.encode_bit(models.regular, regular);
  if (regular) return;
  int64_t previous_difference = 0;
  for (size_t k = 1; k + 1 < count; ++k) {
    const int64_t difference = int64_t(float_bits(times[k])) - int64_t(float_bits(times[k - 1]));
    models.time_delta.encode(encoder, int32_t(difference - previous_difference));
    previous_difference = difference;
  }
}

std::vector<double> as_doubles(const std::vector<float>& times) {
  return std::vector<double>(times.begin(), times.end());
}

// The prediction order whose keys code in fewer bytes from the models' current state (order 1 on a tie).
int cheaper_order(const Models& models, SamplerShape shape, bool all_components,
                  const std::vector<int32_t>& quantized) {
  size_t bytes_of[3] = {0, 0, 0};
  for (int order : {1, 2}) {
    Models scratch = models;
    std::vector<uint8_t> bytes;
    RangeEncoder coder(bytes);
    KeyEncoder encoder{coder};
    std::vector<int32_t> unused;
    shape.order = order;
    code_keys(encoder, scratch, shape, all_components, quantized.data(), unused);
    coder.finish();
    bytes_of[order] = bytes.size();
  }
  return bytes_of[2] < bytes_of[1] ? 2 : 1;
}

// ---- Decoder ----

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

TrackLayout track_layout(const TrackSet& tracks) {
  TrackLayout layout;
  for (const std::vector<float>& times : tracks.times) layout.time_counts.push_back(times.size());
  for (const TrackSampler& sampler : tracks.samplers)
    layout.samplers.push_back({sampler.times, sampler.path, sampler.components});
  return layout;
}

Status encode_tracks(const TrackSet& tracks, const std::vector<double>& steps, std::vector<uint8_t>& bytes,
                     TrackSet& decoded) {
  return encode_tracks_with(tracks, steps, TrackEncoderChoices(), bytes, decoded);
}

Status encode_tracks_with(const TrackSet& tracks, const std::vector<double>& steps, const TrackEncoderChoices& choices,
                          std::vector<uint8_t>& bytes, TrackSet& decoded) {
  assert(choices.order >= 0 && choices.order <= 2);
  SEGMORPH_RETURN_IF_ERROR(check_tracks(tracks, steps));
  std::vector<SamplerPlan> plans(tracks.samplers.size());
  for (size_t s = 0; s < plans.size(); ++s)
    SEGMORPH_RETURN_IF_ERROR(plan_sampler(tracks.samplers[s], steps[s], plans[s]));
  std::vector<std::vector<double>> times;
  for (const std::vector<float>& array : tracks.times) times.push_back(as_doubles(array));

  bytes.assign(std::begin(track_format::kMagic), std::end(track_format::kMagic));
  bytes.push_back(track_format::kVersion);
  RangeEncoder coder(bytes);
  KeyEncoder encoder{coder};
  Models models;
  models.count.encode(coder, uint32_t(tracks.times.size()));
  for (const std::vector<float>& array : tracks.times) encode_times(coder, models, array);
  models.count.encode(coder, uint32_t(tracks.samplers.size()));
  decoded.times = tracks.times;
  decoded.samplers.assign(tracks.samplers.size(), TrackSampler());
  for (size_t s = 0; s < plans.size(); ++s) {
    const TrackSampler& sampler = tracks.samplers[s];
    const SamplerPlan& plan = plans[s];
    models.count.encode(coder, uint32_t(sampler.times));
    coder.encode_direct_bits(uint32_t(sampler.path), 2);
    models.count.encode(coder, uint32_t(sampler.components));
    coder.encode_direct_bits(plan.mantissa, track_format::kStepMantissaBits);
    models.step_exponent.encode(coder, plan.exponent);
    SamplerShape shape{sampler.path, size_t(sampler.components), grid_step(plan.mantissa, plan.exponent),
                       &times[size_t(sampler.times)], 1};
    if (shape.times->size() >= 3) {
      shape.order = choices.order != 0 ? choices.order
                                       : cheaper_order(models, shape, choices.rotation_all_components, plan.quantized);
      coder.encode_bit(models.order, shape.order == 2);
    }
    std::vector<int32_t> q;
    code_keys(encoder, models, shape, choices.rotation_all_components, plan.quantized.data(), q);
    TrackSampler& out = decoded.samplers[s];
    out.path = sampler.path;
    out.components = sampler.components;
    out.times = sampler.times;
    dequantize(shape, q, out.values);
  }
  coder.finish();
  return Status::Ok();
}

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
