#include "encode/track_encoder.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

#include "common/float_bits.h"
#include "common/range_coder.h"
#include "common/track_format.h"
#include "common/track_syntax.h"

namespace segmorph {

using namespace track_code;

namespace {

Status unusable(const std::string& what) {
  return Status(StatusCode::invalid_argument, "tracks: " + what);
}

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

}  // namespace

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

}  // namespace segmorph
