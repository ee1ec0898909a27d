// The syntax of the track stream (spec/tracks.md, section 4) that its encoder (encode/track_encoder.cpp) and decoder
// (decode/track_decoder.cpp) share: the adaptive contexts, the grid of steps, the predictions and one walk over a
// sampler's keys, so that the two cannot disagree on an order, a model or a prediction.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "common/range_coder.h"
#include "common/track_format.h"
#include "common/track_set.h"

namespace segmorph {
namespace track_code {

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

inline bool components_fit(TrackPath path, int components) {
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

inline int slot(size_t component) {
  return int(std::min(component, size_t(kSlots - 1)));
}

inline int bucket(int64_t residual) {
  const uint64_t magnitude = residual < 0 ? uint64_t(-residual) : uint64_t(residual);
  return magnitude == 0 ? 0 : magnitude == 1 ? 1 : magnitude <= 3 ? 2 : 3;
}

// (8 + m) · 2^(e − 3), exact in binary64.
inline double grid_step(uint32_t mantissa, int exponent) {
  return std::ldexp(double(8 + mantissa), exponent - 3);
}

inline int64_t clamp_quantized(int64_t value) {
  return std::clamp(value, -kMaxQuantized, kMaxQuantized);
}

// The nearest integer, halves away from zero, of x clamped to ±2^31 (beyond which every use clamps anyway; the clamp
// also keeps llround defined when x is infinite).
inline int64_t round_clamped(double x) {
  return std::llround(std::clamp(x, -2147483648.0, 2147483648.0));
}

// Regular times: key k of `count` keys from first to last, in binary64 in this order, rounded to binary32.
inline float regular_time(double first, double last, size_t k, size_t count) {
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

inline int64_t identity(const SamplerShape& shape, size_t component) {
  const bool one = shape.path == TrackPath::scale || (shape.path == TrackPath::rotation && component == 3);
  return one ? clamp_quantized(round_clamped(1.0 / shape.step)) : 0;
}

// The prediction of component c of key k from the decoded keys before it (q: keys × components).
inline int64_t predict(const SamplerShape& shape, const std::vector<int32_t>& q, size_t k, size_t c) {
  if (k == 0) return identity(shape, c);
  const int64_t q1 = q[(k - 1) * shape.components + c];
  if (k == 1 || shape.order == 1) return q1;
  const int64_t q0 = q[(k - 2) * shape.components + c];
  const std::vector<double>& t = *shape.times;
  const double extrapolated = (double(q1 - q0) * (t[k] - t[k - 1])) / (t[k - 1] - t[k - 2]);
  return clamp_quantized(q1 + round_clamped(extrapolated));
}

// The rotation component to rebuild: the largest predicted magnitude, the first of equals.
inline size_t largest(const int64_t* prediction) {
  size_t m = 0;
  for (size_t c = 1; c < 4; ++c)
    if (std::llabs(prediction[c]) > std::llabs(prediction[m])) m = c;
  return m;
}

// Component m of a unit quaternion from the other three (q: the key's 4 quantized components), with the sign of
// its prediction.
inline int64_t rebuild(const int32_t* q, size_t m, int64_t prediction, double step) {
  double sum = 0.0;
  for (size_t c = 0; c < 4; ++c)
    if (c != m) {
      const double x = double(q[c]) * step;
      sum = sum + x * x;
    }
  const int64_t magnitude = clamp_quantized(round_clamped(std::sqrt(std::max(0.0, 1.0 - sum)) / step));
  return prediction < 0 ? -magnitude : magnitude;
}

// Encoder and decoder walk the keys with this one function: the encoder's Coder (KeyEncoder, track_encoder.cpp)
// codes the symbol it is given, the decoder's (KeyDecoder, track_decoder.cpp) overwrites it with the one it reads.
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
inline void dequantize(const SamplerShape& shape, const std::vector<int32_t>& q, std::vector<float>& values) {
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

inline std::vector<double> as_doubles(const std::vector<float>& times) {
  return std::vector<double>(times.begin(), times.end());
}

}  // namespace track_code
}  // namespace segmorph
