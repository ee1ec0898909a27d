// The track stream (codec/encode/track_encoder.h, codec/decode/track_decoder.h, spec/tracks.md): accuracy of each path, exact times, the decoder's
// agreement with the encoder, determinism, the step grid and its limits, layouts that disagree, hostile bytes, and
// what the encoder's choices (rotation components rebuilt, prediction order) are worth on smooth tracks.
#include "common/track_set.h"
#include "decode/track_decoder.h"
#include "encode/track_encoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include "common/range_coder.h"
#include "common/track_format.h"

namespace segmorph {
namespace {

constexpr double kPi = 3.14159265358979323846;

uint32_t bits(float x) {
  uint32_t b;
  std::memcpy(&b, &x, 4);
  return b;
}

// `count` keys at 30 per second, each float(k / 30) as exporters write them.
std::vector<float> frame_times(size_t count) {
  std::vector<float> times;
  for (size_t k = 0; k < count; ++k) times.push_back(float(double(k) / 30.0));
  return times;
}

// Increasing times with uneven gaps (0.01 to 0.2 s), from 0.
std::vector<float> uneven_times(size_t count, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> gap(0.01, 0.2);
  std::vector<float> times = {0.0f};
  while (times.size() < count) times.push_back(float(times.back() + gap(random)));
  return times;
}

TrackSampler translation_track(int times, const std::vector<float>& t) {
  TrackSampler s{TrackPath::translation, 3, times, {}};
  for (float x : t) s.values.insert(s.values.end(), {float(std::sin(x)), float(0.5 * std::cos(2 * x)), 0.3f * x});
  return s;
}

TrackSampler scale_track(int times, const std::vector<float>& t) {
  TrackSampler s{TrackPath::scale, 3, times, {}};
  for (float x : t)
    s.values.insert(s.values.end(), {float(1 + 0.2 * std::sin(x)), float(1 + 0.1 * std::cos(3 * x)), 2.0f});
  return s;
}

TrackSampler weights_track(int times, const std::vector<float>& t, int targets) {
  TrackSampler s{TrackPath::weights, targets, times, {}};
  for (float x : t)
    for (int c = 0; c < targets; ++c) s.values.push_back(float(0.5 + 0.5 * std::sin(x * (1 + 0.3 * c) + c)));
  return s;
}

// A smooth turn: about an axis that swings slowly, by an angle that grows then eases.
TrackSampler rotation_track(int times, const std::vector<float>& t) {
  TrackSampler s{TrackPath::rotation, 4, times, {}};
  for (float x : t) {
    const double angle = 3.0 * std::sin(0.7 * x) + 0.5 * x;
    double axis[3] = {std::cos(0.4 * x), std::sin(0.4 * x), 0.5 + 0.3 * std::sin(x)};
    const double length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    const double half = std::sin(angle / 2) / length;
    s.values.insert(s.values.end(),
                    {float(axis[0] * half), float(axis[1] * half), float(axis[2] * half), float(std::cos(angle / 2))});
  }
  return s;
}

struct Encoded {
  std::vector<uint8_t> bytes;
  TrackSet decoded;
};

Encoded encode(const TrackSet& tracks, const std::vector<double>& steps, TrackEncoderChoices choices = {}) {
  Encoded e;
  const Status status = encode_tracks_with(tracks, steps, choices, e.bytes, e.decoded);
  EXPECT_TRUE(status.ok()) << status.message();
  return e;
}

Status decode(const std::vector<uint8_t>& bytes, const TrackLayout& layout, TrackSet& out) {
  return decode_tracks(bytes.data(), bytes.size(), layout, out);
}

void expect_identical(const TrackSet& a, const TrackSet& b) {
  ASSERT_EQ(a.times.size(), b.times.size());
  for (size_t i = 0; i < a.times.size(); ++i) {
    ASSERT_EQ(a.times[i].size(), b.times[i].size());
    for (size_t k = 0; k < a.times[i].size(); ++k) EXPECT_EQ(bits(a.times[i][k]), bits(b.times[i][k]));
  }
  ASSERT_EQ(a.samplers.size(), b.samplers.size());
  for (size_t s = 0; s < a.samplers.size(); ++s) {
    EXPECT_EQ(a.samplers[s].path, b.samplers[s].path);
    EXPECT_EQ(a.samplers[s].components, b.samplers[s].components);
    EXPECT_EQ(a.samplers[s].times, b.samplers[s].times);
    ASSERT_EQ(a.samplers[s].values.size(), b.samplers[s].values.size());
    for (size_t i = 0; i < a.samplers[s].values.size(); ++i)
      ASSERT_EQ(bits(a.samplers[s].values[i]), bits(b.samplers[s].values[i])) << "sampler " << s << ", value " << i;
  }
}

// Angle in radians between two rotations given as quaternions (either sign).
double rotation_angle(const float* a, const float* b) {
  double dot = 0, na = 0, nb = 0;
  for (int c = 0; c < 4; ++c) {
    dot += double(a[c]) * b[c];
    na += double(a[c]) * a[c];
    nb += double(b[c]) * b[c];
  }
  return 2 * std::acos(std::min(1.0, std::fabs(dot) / std::sqrt(na * nb)));
}

// Every kind of sampler on two time arrays.
TrackSet mixed_tracks() {
  TrackSet tracks;
  tracks.times = {frame_times(61), uneven_times(40, 3)};
  tracks.samplers = {translation_track(0, tracks.times[0]), rotation_track(0, tracks.times[0]),
                     scale_track(1, tracks.times[1]), weights_track(1, tracks.times[1], 5),
                     rotation_track(1, tracks.times[1])};
  return tracks;
}

const std::vector<double> kMixedSteps = {1e-3, 1e-4, 1e-3, 1.0 / 256, 3e-4};

TEST(TrackCoding, DecodesToTheEncodersValuesWithinHalfAStep) {
  const TrackSet tracks = mixed_tracks();
  const Encoded e = encode(tracks, kMixedSteps);
  TrackSet decoded;
  const Status status = decode(e.bytes, track_layout(tracks), decoded);
  ASSERT_TRUE(status.ok()) << status.message();
  expect_identical(decoded, e.decoded);
  for (size_t s = 0; s < tracks.samplers.size(); ++s) {
    if (tracks.samplers[s].path == TrackPath::rotation) continue;
    const std::vector<float>& original = tracks.samplers[s].values;
    for (size_t i = 0; i < original.size(); ++i)  // the grid's step is at most the requested one; then a float rounding
      EXPECT_LE(std::fabs(double(decoded.samplers[s].values[i]) - original[i]),
                kMixedSteps[s] / 2 + std::fabs(original[i]) * 0x1p-24)
          << "sampler " << s << ", value " << i;
  }
  printf("5 samplers, 242 keys: %zu bytes\n", e.bytes.size());
}

TEST(TrackCoding, RotationsStayWithinAFewStepsOfTheOriginalAngle) {
  const TrackSet tracks = mixed_tracks();
  const Encoded e = encode(tracks, kMixedSteps);
  for (size_t s : {1u, 4u}) {
    const TrackSampler& original = tracks.samplers[s];
    double worst = 0;
    for (size_t k = 0; k < original.values.size(); k += 4) {
      worst = std::max(worst, rotation_angle(&original.values[k], &e.decoded.samplers[s].values[k]));
      double norm = 0;
      for (int c = 0; c < 4; ++c)
        norm += double(e.decoded.samplers[s].values[k + c]) * e.decoded.samplers[s].values[k + c];
      EXPECT_NEAR(norm, 1.0, 1e-6);
    }
    // Each component within half a step, the rebuilt one within kMaxRebuildError steps: about 2 · 2.5 steps of angle.
    EXPECT_LT(worst, 6 * kMixedSteps[s]) << "sampler " << s;
    EXPECT_GT(worst, 0.01 * kMixedSteps[s]) << "sampler " << s << ": suspiciously exact";
  }
}

TEST(TrackCoding, KeyTimesDecodeBitExact) {
  TrackSet tracks;
  std::vector<float> regular;
  for (size_t k = 0; k < 50; ++k) regular.push_back(float(0.5 + (double(k) * 1.5) / 49));
  std::vector<float> crossing;  // patterns across exponents, a subnormal and +0
  for (float t : {0.0f, 1e-40f, 1e-30f, 0.24f, 0.25f, 0.26f, 0.5f, 0.99f, 1.0f, 1.01f, 3.0f, 3.0000002f, 1e6f})
    crossing.push_back(t);
  tracks.times = {frame_times(100), regular, uneven_times(64, 9), crossing, {2.5f}, {0.0f, 1.0f}};
  for (int i = 0; i < 6; ++i) tracks.samplers.push_back(translation_track(i, tracks.times[size_t(i)]));
  const Encoded e = encode(tracks, std::vector<double>(6, 1e-3));
  TrackSet decoded;
  ASSERT_TRUE(decode(e.bytes, track_layout(tracks), decoded).ok());
  expect_identical(decoded, e.decoded);
  for (size_t i = 0; i < tracks.times.size(); ++i)
    for (size_t k = 0; k < tracks.times[i].size(); ++k)
      EXPECT_EQ(bits(decoded.times[i][k]), bits(tracks.times[i][k])) << "array " << i << ", key " << k;
}

// A time array alone: an evenly spaced one costs its first and last key and a bit, an uneven one its gaps.
TEST(TrackCoding, RegularTimesCostTheirEndsOnly) {
  TrackSet regular, uneven;
  std::vector<float> times;
  for (size_t k = 0; k < 200; ++k) times.push_back(float(0.25 + (double(k) * 4.0) / 199));
  regular.times = {times};
  uneven.times = {uneven_times(200, 4)};
  const Encoded a = encode(regular, {}), b = encode(uneven, {});
  printf("200 keys: evenly spaced %zu bytes, uneven %zu bytes\n", a.bytes.size(), b.bytes.size());
  EXPECT_LE(a.bytes.size(), 17u);  // header 5, two 32-bit times, counts and the bit
  EXPECT_GT(b.bytes.size(), 200u);
}

TEST(TrackCoding, TwoEncodesAreByteIdentical) {
  const TrackSet tracks = mixed_tracks();
  EXPECT_EQ(encode(tracks, kMixedSteps).bytes, encode(tracks, kMixedSteps).bytes);
}

// glTF plays q and −q alike: keys whose sign flips code as the sign-continuous track, byte for byte.
TEST(TrackCoding, RotationSignFlipsCodeAsTheContinuousTrack) {
  TrackSet tracks;
  tracks.times = {frame_times(90)};
  tracks.samplers = {rotation_track(0, tracks.times[0])};
  TrackSet flipped = tracks;
  std::mt19937 random(5);
  int flips = 0;
  for (size_t k = 4; k < flipped.samplers[0].values.size(); k += 4)
    if (random() % 2) {
      ++flips;
      for (size_t c = 0; c < 4; ++c) flipped.samplers[0].values[k + c] = -flipped.samplers[0].values[k + c];
    }
  ASSERT_GT(flips, 20);
  const Encoded a = encode(tracks, {1e-4}), b = encode(flipped, {1e-4});
  EXPECT_EQ(a.bytes, b.bytes);
  expect_identical(a.decoded, b.decoded);
  // The whole track negated, key 0 too: key 0 takes the sign nearer the identity (w > 0 here).
  TrackSet negated = tracks;
  for (float& x : negated.samplers[0].values) x = -x;
  ASSERT_GT(tracks.samplers[0].values[3], 0.0f);
  EXPECT_EQ(encode(negated, {1e-4}).bytes, a.bytes);
}

TEST(TrackCoding, StepsAreRoundedDownToTheGrid) {
  TrackSet tracks;
  tracks.times = {{0.0f, 1.0f, 2.0f}};
  tracks.samplers = {{TrackPath::translation, 3, 0, {0.1f, 0.2f, -0.3f, 1.0f, 0.0f, 0.09375f, 7.0f, 7.5f, 8.0f}}};
  // 0.1 = 0.8 · 2^-3: e = −4, m = floor(12.8) − 8 = 4, step 12 · 2^-7 = 0.09375.
  const Encoded e = encode(tracks, {0.1});
  const std::vector<float> want = {0.09375f, 0.1875f, -0.28125f, 1.03125f, 0.0f, 0.09375f, 7.03125f, 7.5f, 7.96875f};
  for (size_t i = 0; i < want.size(); ++i) EXPECT_EQ(e.decoded.samplers[0].values[i], want[i]) << i;
  // A step on the grid is kept as it is: 0.375 = 12 · 2^-5.
  const Encoded exact = encode(tracks, {0.375});
  EXPECT_EQ(exact.decoded.samplers[0].values[6], 7.125f);  // 19 · 0.375
}

TEST(TrackCoding, StepLimits) {
  TrackSet tracks;
  tracks.times = {{0.0f}};
  tracks.samplers = {{TrackPath::translation, 3, 0, {1e-9f, 0.0f, 0.0f}}};
  std::vector<uint8_t> bytes;
  TrackSet decoded;
  EXPECT_TRUE(encode_tracks(tracks, {0x1p-40}, bytes, decoded).ok());
  EXPECT_EQ(encode_tracks(tracks, {0x1.fffffffffffffp-41}, bytes, decoded).code(), StatusCode::invalid_argument);
  EXPECT_TRUE(encode_tracks(tracks, {0x1.fffffffffffffp+20}, bytes, decoded).ok());  // 15 · 2^17 on the grid
  EXPECT_EQ(encode_tracks(tracks, {0x1p+21}, bytes, decoded).code(), StatusCode::invalid_argument);
  for (double bad : {0.0, -1.0, double(NAN), double(INFINITY)})
    EXPECT_EQ(encode_tracks(tracks, {bad}, bytes, decoded).code(), StatusCode::invalid_argument) << bad;
  // Values whose quantizer index passes 2^30 − 1 are refused, not wrapped.
  tracks.samplers[0].values = {1073741823.0f * 0.5f, 0.0f, 0.0f};
  EXPECT_TRUE(encode_tracks(tracks, {1.0}, bytes, decoded).ok());
  tracks.samplers[0].values = {1073741824.0f, 0.0f, 0.0f};
  EXPECT_EQ(encode_tracks(tracks, {1.0}, bytes, decoded).code(), StatusCode::invalid_argument);
  tracks.samplers[0].values = {1.0f, NAN, 0.0f};
  EXPECT_EQ(encode_tracks(tracks, {1.0}, bytes, decoded).code(), StatusCode::invalid_argument);
}

TEST(TrackCoding, UnusableInputIsRefused) {
  const TrackSet good = mixed_tracks();
  std::vector<uint8_t> bytes;
  TrackSet decoded;
  auto refused = [&](const TrackSet& tracks) {
    const Status status = encode_tracks(tracks, kMixedSteps, bytes, decoded);
    return status.code() == StatusCode::invalid_argument && !status.message().empty();
  };
  TrackSet t = good;
  t.times[0][5] = t.times[0][4];
  EXPECT_TRUE(refused(t)) << "times not increasing";
  t = good;
  t.times[0][0] = -0.0f;
  EXPECT_TRUE(refused(t)) << "-0";
  t = good;
  t.samplers[2].components = 4;
  EXPECT_TRUE(refused(t)) << "scale with 4 components";
  t = good;
  t.samplers[0].times = 2;
  EXPECT_TRUE(refused(t)) << "no such time array";
  t = good;
  t.samplers[3].values.pop_back();
  EXPECT_TRUE(refused(t)) << "values not keys × components";
  t = good;
  for (size_t c = 0; c < 4; ++c) t.samplers[1].values[8 + c] = 0.0f;
  EXPECT_TRUE(refused(t)) << "a zero quaternion";
  EXPECT_EQ(encode_tracks(good, {1e-3}, bytes, decoded).code(), StatusCode::invalid_argument);
}

// ---- Hostile streams ----

TrackSet small_tracks() {
  TrackSet tracks;
  tracks.times = {{0.0f, 0.5f, 1.25f, 2.0f}};
  tracks.samplers = {translation_track(0, tracks.times[0]), rotation_track(0, tracks.times[0])};
  return tracks;
}

TEST(TrackCodingHostile, EveryPrefixAndTrailingBytesAreRefused) {
  const TrackSet tracks = small_tracks();
  const Encoded e = encode(tracks, {1e-3, 1e-3});
  const TrackLayout layout = track_layout(tracks);
  TrackSet decoded;
  ASSERT_TRUE(decode(e.bytes, layout, decoded).ok());
  for (size_t size = 0; size < e.bytes.size(); ++size) {
    const Status status = decode_tracks(e.bytes.data(), size, layout, decoded);
    EXPECT_EQ(status.code(), StatusCode::bad_data) << "prefix of " << size << " bytes";
  }
  std::vector<uint8_t> longer = e.bytes;
  longer.push_back(0);
  EXPECT_EQ(decode(longer, layout, decoded).code(), StatusCode::bad_data);
  std::vector<uint8_t> version = e.bytes;
  version[4] = 2;
  EXPECT_EQ(decode(version, layout, decoded).code(), StatusCode::unsupported);
  std::vector<uint8_t> magic = e.bytes;
  magic[3] = 'A';  // the animation stream's magic
  EXPECT_EQ(decode(magic, layout, decoded).code(), StatusCode::bad_data);
}

TEST(TrackCodingHostile, LayoutsThatDisagreeAreRefusedWithAMessage) {
  const TrackSet tracks = small_tracks();
  const Encoded e = encode(tracks, {1e-3, 1e-3});
  const TrackLayout good = track_layout(tracks);
  auto message = [&](const TrackLayout& layout) {
    TrackSet decoded;
    const Status status = decode(e.bytes, layout, decoded);
    EXPECT_EQ(status.code(), StatusCode::bad_data);
    EXPECT_EQ(status.message().find('\n'), std::string::npos);
    return status.message();
  };
  TrackLayout layout = good;
  layout.time_counts[0] = 5;
  EXPECT_NE(message(layout).find("has 4 keys, the file says 5"), std::string::npos) << message(layout);
  layout = good;
  layout.time_counts.push_back(4);
  EXPECT_NE(message(layout).find("1 key-time arrays, the file says 2"), std::string::npos) << message(layout);
  layout = good;
  layout.samplers.pop_back();
  EXPECT_NE(message(layout).find("2 samplers, the file says 1"), std::string::npos) << message(layout);
  layout = good;
  layout.samplers[0].path = TrackPath::scale;
  EXPECT_NE(message(layout).find("sampler 0: "), std::string::npos) << message(layout);
  layout = good;
  layout.samplers[1].path = TrackPath::weights;  // 4 components fit weights
  EXPECT_NE(message(layout).find("sampler 1: "), std::string::npos) << message(layout);
  layout = good;
  layout.samplers[1].components = 3;  // a rotation of 3: the layout itself is wrong
  EXPECT_NE(message(layout).find("component count"), std::string::npos) << message(layout);
  layout = good;
  layout.samplers[0].times = 1;
  EXPECT_NE(message(layout).find("key-time array"), std::string::npos) << message(layout);
}

TEST(TrackCodingHostile, RandomByteFlipsNeverCrash) {
  const TrackSet tracks = mixed_tracks();
  const Encoded e = encode(tracks, kMixedSteps);
  const TrackLayout layout = track_layout(tracks);
  std::mt19937 random(17);
  size_t refused = 0;
  const int trials = 3000;
  for (int trial = 0; trial < trials; ++trial) {
    std::vector<uint8_t> bytes = e.bytes;
    for (int flips = 1 + int(random() % 4); flips > 0; --flips)
      bytes[random() % bytes.size()] ^= uint8_t(1 + random() % 255);
    TrackSet decoded;
    const Status status = decode(bytes, layout, decoded);
    if (!status.ok()) {
      ++refused;
      EXPECT_EQ(status.message().find('\n'), std::string::npos);
      continue;
    }
    ASSERT_EQ(decoded.samplers.size(), tracks.samplers.size());
    for (const TrackSampler& s : decoded.samplers)
      for (float x : s.values) ASSERT_TRUE(std::isfinite(x));
  }
  EXPECT_GT(refused, size_t(trials) * 95 / 100);
}

// ---- Hand-built streams: checks the encoder never needs ----

// The symbols of a stream up to and including the first sampler's step exponent, for one time array of one key
// (0.0) and one translation sampler, coded as spec/tracks.md section 5 says with the models of section 4.
struct HandStream {
  std::vector<uint8_t> bytes = {'S', 'G', 'M', 'T', 1};
  RangeEncoder encoder{bytes};
  UnsignedModel count;
  SignedModel step_exponent;
  std::array<SignedModel, 3> first_key;

  explicit HandStream(int exponent) {
    count.encode(encoder, 1);  // time arrays
    count.encode(encoder, 1);  // keys
    encoder.encode_direct_bits(0, 32);
    count.encode(encoder, 1);  // samplers
    count.encode(encoder, 0);  // its time array
    encoder.encode_direct_bits(uint32_t(TrackPath::translation), 2);
    count.encode(encoder, 3);
    encoder.encode_direct_bits(0, 3);  // m
    step_exponent.encode(encoder, exponent);
  }
  std::vector<uint8_t> finish(int32_t x) {
    first_key[0].encode(encoder, x);
    first_key[1].encode(encoder, 0);
    first_key[2].encode(encoder, 0);
    encoder.finish();
    return bytes;
  }
};

TrackLayout one_translation() {
  TrackLayout layout;
  layout.time_counts = {1};
  layout.samplers = {{0, TrackPath::translation, 3}};
  return layout;
}

TEST(TrackCodingHostile, HandBuiltStreamsAtTheLimits) {
  TrackSet decoded;
  // e = 20, x = 2^30 − 1: the largest step and value; the decoded value is (2^30 − 1) · 2^17, rounded to binary32.
  Status status = decode(HandStream(20).finish(1073741823), one_translation(), decoded);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(decoded.samplers[0].values[0], float(1073741823.0 * 0x1p20));  // step 8 · 2^17
  status = decode(HandStream(-40).finish(-5), one_translation(), decoded);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(decoded.samplers[0].values[0], float(-5 * 0x1p-40));
  // One past each limit.
  status = decode(HandStream(21).finish(1), one_translation(), decoded);
  EXPECT_NE(status.message().find("step"), std::string::npos) << status.message();
  status = decode(HandStream(-41).finish(1), one_translation(), decoded);
  EXPECT_NE(status.message().find("step"), std::string::npos) << status.message();
  status = decode(HandStream(0).finish(1073741824), one_translation(), decoded);
  EXPECT_NE(status.message().find("out of range"), std::string::npos) << status.message();
  status = decode(HandStream(0).finish(-1073741824), one_translation(), decoded);
  EXPECT_NE(status.message().find("out of range"), std::string::npos) << status.message();
}

// ---- What the encoder's choices are worth ----

size_t bytes_with(const TrackSet& tracks, const std::vector<double>& steps, TrackEncoderChoices choices) {
  return encode(tracks, steps, choices).bytes.size();
}

// A second of smooth rotation at 30 and at 60 keys per second, per sampler, as bits per key.
TEST(TrackCodingChoices, ThreeRotationComponentsBeatFour) {
  for (size_t keys : {31u, 61u, 241u}) {
    TrackSet tracks;
    std::vector<float> t;
    for (size_t k = 0; k < keys; ++k) t.push_back(float(4.0 * double(k) / double(keys - 1)));
    tracks.times = {t};
    tracks.samplers = {rotation_track(0, t)};
    for (double step : {1e-3, 1e-4}) {
      TrackEncoderChoices three, four;
      four.rotation_all_components = true;
      const size_t a = bytes_with(tracks, {step}, three), b = bytes_with(tracks, {step}, four);
      printf("rotation, %zu keys over 4 s, step %g: 3 components %.2f bits/key, 4 components %.2f bits/key\n", keys,
             step, 8.0 * double(a) / double(keys), 8.0 * double(b) / double(keys));
      EXPECT_LT(a, b) << keys << " keys, step " << step;
    }
  }
}

TEST(TrackCodingChoices, OrderTwoBeatsOrderOneOnSmoothTracksAndTheEncoderPicksIt) {
  std::vector<float> t;
  for (size_t k = 0; k < 121; ++k) t.push_back(float(double(k) / 30.0));
  const std::vector<std::pair<const char*, TrackSampler>> samplers = {{"translation", translation_track(0, t)},
                                                                      {"rotation", rotation_track(0, t)},
                                                                      {"scale", scale_track(0, t)},
                                                                      {"weights (4)", weights_track(0, t, 4)}};
  for (const auto& [name, sampler] : samplers) {
    TrackSet tracks;
    tracks.times = {t};
    tracks.samplers = {sampler};
    TrackEncoderChoices first, second, automatic;
    first.order = 1;
    second.order = 2;
    const double step = sampler.path == TrackPath::rotation ? 1e-4 : 1e-3;
    const size_t a = bytes_with(tracks, {step}, first), b = bytes_with(tracks, {step}, second),
                 c = bytes_with(tracks, {step}, automatic);
    printf("%s, 121 keys at 30/s, step %g: order 1 %.2f bits/key, order 2 %.2f bits/key, encoder's choice %zu bytes\n",
           name, step, 8.0 * double(a) / 121, 8.0 * double(b) / 121, c);
    EXPECT_LT(b, a) << name;
    EXPECT_EQ(c, std::min(a, b)) << name;
  }
  // A step track: order 2 overshoots at each jump, order 1 wins.
  TrackSet steps;
  steps.times = {t};
  steps.samplers = {{TrackPath::translation, 3, 0, {}}};
  for (size_t k = 0; k < t.size(); ++k)
    steps.samplers[0].values.insert(steps.samplers[0].values.end(), {float(k / 10), 0.0f, 0.0f});
  TrackEncoderChoices first, second;
  first.order = 1;
  second.order = 2;
  EXPECT_LT(bytes_with(steps, {1e-3}, first), bytes_with(steps, {1e-3}, second));
  EXPECT_EQ(bytes_with(steps, {1e-3}, {}), bytes_with(steps, {1e-3}, first));
}

}  // namespace
}  // namespace segmorph
