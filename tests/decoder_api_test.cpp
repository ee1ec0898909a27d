// The runtime decoder's API (include/segmorph/decoder.h, decoder_c.h): whole clips, frame by frame and seeks give
// the frames decode_animation gives, bit for bit, for every kind of stream (lossy and lossless, both residual codes,
// several clips); kept targets; track streams; every bad argument and bad stream refused with its status and a
// one-line message, and the decoder reusable afterwards.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "common/stream_format.h"
#include "common/track_set.h"
#include "decode/frame_decoder.h"
#include "decode/track_decoder.h"
#include "encode/encoder.h"
#include "encode/track_encoder.h"
#include "segmorph/decoder.h"
#include "segmorph/decoder_c.h"
#include "test_meshes.h"

namespace segmorph {
namespace {

// One encoded primitive: its clips, the base a decoder has, and the stream.
struct Case {
  std::string name;
  std::vector<FrameSequence> clips;
  std::vector<float> base;
  std::vector<uint8_t> stream;
};

std::vector<Case> cases() {
  struct Kind {
    const char* name;
    RateMode mode;
    bool table;
    std::vector<size_t> frames;
    bool version_4 = false;  // the GPU-playable model (a version-4 stream whatever its size)
  };
  const Kind kinds[] = {{"lossy, one clip", RateMode::error, false, {9}},
                        {"lossy, three clips", RateMode::error, false, {5, 1, 8}},
                        {"table code, three clips", RateMode::error, true, {4, 7, 3}},
                        {"lossless, two clips", RateMode::lossless, false, {6, 3}},
                        {"version 4, four clips", RateMode::error, false, {17, 1, 8, 10}, true}};
  std::vector<Case> out;
  for (const Kind& kind : kinds) {
    Case c;
    c.name = kind.name;
    for (size_t i = 0; i < kind.frames.size(); ++i)
      c.clips.push_back(testing::bending_clip(kind.frames[i], 0.8 + 0.3 * double(i), double(i)));
    c.base = testing::quantized_base(c.clips[0]);
    CodecSettings settings;
    settings.mode = kind.mode;
    settings.target = 0.3;
    settings.table_residuals = kind.table;
    settings.gpu_playable = kind.version_4;
    c.stream = testing::encode(c.clips, c.base, settings).stream;
    if (kind.version_4) {
      EXPECT_EQ(c.stream[4], format::kTransformVersion) << kind.name;
    }
    out.push_back(std::move(c));
  }
  return out;
}

// What decode_animation gives: the reference.
std::vector<FrameSequence> reference(const Case& c) {
  std::vector<FrameSequence> clips;
  const Status status = decode_animation(c.stream.data(), c.stream.size(), c.base, c.clips[0].triangles, clips);
  EXPECT_TRUE(status.ok()) << status.message();
  return clips;
}

bool same_bits(const float* a, const float* b, size_t count) { return std::memcmp(a, b, count * sizeof(float)) == 0; }

segmorph_status open(segmorph_decoder* decoder, const Case& c) {
  return segmorph_decoder_open(decoder, c.stream.data(), c.stream.size(), c.base.data(), c.base.size() / 3,
                               c.clips[0].triangles.data(), c.clips[0].triangles.size());
}

TEST(DecoderApi, WholeClipsAreTheReferenceFrames) {
  for (const Case& c : cases()) {
    const std::vector<FrameSequence> expected = reference(c);
    segmorph_decoder* decoder = segmorph_decoder_create();
    ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK) << c.name << ": " << segmorph_decoder_message(decoder);
    ASSERT_EQ(segmorph_decoder_clip_count(decoder), expected.size()) << c.name;
    EXPECT_EQ(segmorph_decoder_vertex_count(decoder), c.base.size() / 3);
    EXPECT_EQ(segmorph_decoder_lossless(decoder), c.name.find("lossless") != std::string::npos ? 1 : 0);
    // The stream's own version byte (1, 2 with the table code; 3 where the encoder used version 3's tools).
    EXPECT_EQ(segmorph_decoder_stream_version(decoder), int(c.stream[4]));
    EXPECT_GE(segmorph_decoder_stream_version(decoder), c.name.find("table") != std::string::npos ? 2 : 1);
    // In stream order, then backwards (seeking back to checkpoints), then the first again.
    std::vector<size_t> order;
    for (size_t clip = 0; clip < expected.size(); ++clip) order.push_back(clip);
    for (size_t clip = expected.size(); clip-- > 0;) order.push_back(clip);
    for (size_t clip : order) {
      const size_t floats = segmorph_decode_clip_bound(decoder, clip);
      ASSERT_EQ(floats, expected[clip].positions.size());
      EXPECT_EQ(segmorph_decoder_frame_count(decoder, clip), expected[clip].frame_count);
      std::vector<float> frames(floats, -1.0f);
      ASSERT_EQ(segmorph_decode_clip(decoder, clip, frames.data(), frames.size()), SEGMORPH_STATUS_OK)
          << c.name << ": " << segmorph_decoder_message(decoder);
      EXPECT_TRUE(same_bits(frames.data(), expected[clip].positions.data(), floats)) << c.name << ", clip " << clip;
      EXPECT_STREQ(segmorph_decoder_message(decoder), "");
    }
    segmorph_decoder_destroy(decoder);
  }
}

TEST(DecoderApi, FrameByFrameIsTheReferenceFramesWhereverItStarts) {
  for (const Case& c : cases()) {
    const std::vector<FrameSequence> expected = reference(c);
    AnimationDecoder decoder;
    ASSERT_TRUE(decoder.open(c.stream.data(), c.stream.size(), c.base.data(), c.base.size() / 3,
                             c.clips[0].triangles.data(), c.clips[0].triangles.size())
                    .ok());
    const size_t frame_floats = c.base.size() / 3 * 3;
    std::vector<float> frame(frame_floats);
    // The whole stream frame by frame: each frame in its place, the position advancing clip by clip.
    for (size_t clip = 0; clip < expected.size(); ++clip)
      for (size_t f = 0; f < expected[clip].frame_count; ++f) {
        ASSERT_EQ(decoder.next_clip(), clip);
        ASSERT_EQ(decoder.next_frame(), f);
        const Status status = decoder.decode_frame(frame.data(), frame.size());
        ASSERT_TRUE(status.ok()) << c.name << ": " << status.message();
        EXPECT_TRUE(same_bits(frame.data(), expected[clip].frame(f), frame_floats))
            << c.name << ", clip " << clip << " frame " << f;
      }
    EXPECT_EQ(decoder.next_clip(), expected.size());
    EXPECT_EQ(decoder.decode_frame(frame.data(), frame.size()).code(), StatusCode::invalid_argument);
    // Seeks to every clip from everywhere: half a clip decoded, then another clip from its start.
    for (size_t from = 0; from < expected.size(); ++from)
      for (size_t to = 0; to < expected.size(); ++to) {
        ASSERT_TRUE(decoder.seek(from).ok());
        for (size_t f = 0; f < (expected[from].frame_count + 1) / 2; ++f)
          ASSERT_TRUE(decoder.decode_frame(frame.data(), frame.size()).ok());
        ASSERT_TRUE(decoder.seek(to).ok()) << c.name;
        for (size_t f = 0; f < expected[to].frame_count; ++f) {
          ASSERT_TRUE(decoder.decode_frame(frame.data(), frame.size()).ok());
          EXPECT_TRUE(same_bits(frame.data(), expected[to].frame(f), frame_floats))
              << c.name << ", from clip " << from << " to clip " << to << " frame " << f;
        }
      }
  }
}

TEST(DecoderApi, AFreshDecoderSeeksForwardToALaterClip) {
  for (const Case& c : cases()) {
    const std::vector<FrameSequence> expected = reference(c);
    const size_t last = expected.size() - 1;
    AnimationDecoder decoder;
    ASSERT_TRUE(decoder.open(c.stream.data(), c.stream.size(), c.base.data(), c.base.size() / 3,
                             c.clips[0].triangles.data(), c.clips[0].triangles.size())
                    .ok());
    std::vector<float> frames(decoder.clip_floats(last));
    ASSERT_TRUE(decoder.decode_clip(last, frames.data(), frames.size()).ok());
    EXPECT_TRUE(same_bits(frames.data(), expected[last].positions.data(), frames.size())) << c.name;
  }
}

TEST(DecoderApi, KeptTargetsAreFramesMinusTheBase) {
  const Case c = cases()[0];
  const std::vector<FrameSequence> expected = reference(c);
  segmorph_decoder* decoder = segmorph_decoder_create();
  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK);
  std::vector<float> targets(segmorph_decode_clip_bound(decoder, 0));
  ASSERT_EQ(segmorph_decode_targets(decoder, targets.data(), targets.size()), SEGMORPH_STATUS_OK);
  for (size_t t = 0; t < expected[0].frame_count; ++t)
    for (size_t i = 0; i < c.base.size(); ++i) {
      const float delta = expected[0].frame(t)[i] - c.base[i];
      ASSERT_EQ(std::memcmp(&targets[t * c.base.size() + i], &delta, 4), 0) << "target " << t << " float " << i;
    }
  // Targets come from one clip: a stream of three is refused.
  ASSERT_EQ(open(decoder, cases()[1]), SEGMORPH_STATUS_OK);
  targets.resize(segmorph_decode_clip_bound(decoder, 0));
  EXPECT_EQ(segmorph_decode_targets(decoder, targets.data(), targets.size()), SEGMORPH_STATUS_BAD_DATA);
  EXPECT_NE(std::string(segmorph_decoder_message(decoder)).find("one clip"), std::string::npos);
  segmorph_decoder_destroy(decoder);
}

// A message is one line and says something.
void expect_one_line(const char* message) {
  EXPECT_GT(std::strlen(message), 0u);
  EXPECT_EQ(std::strchr(message, '\n'), nullptr) << message;
}

// A rotation about z by `angle` of V × 3 floats.
std::vector<float> rotated(const std::vector<float>& x, double angle) {
  std::vector<float> out(x.size());
  for (size_t i = 0; i < x.size(); i += 3) {
    out[i] = float(std::cos(angle) * x[i] - std::sin(angle) * x[i + 1]);
    out[i + 1] = float(std::sin(angle) * x[i] + std::cos(angle) * x[i + 1]);
    out[i + 2] = x[i + 2];
  }
  return out;
}

TEST(DecoderApi, NormalsTurnWithTheSurface) {
  for (const Case& c : cases()) {
    segmorph_decoder* decoder = segmorph_decoder_create();
    ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK) << c.name;
    const size_t floats = c.base.size();
    // The base surface's normals: unit, and outward on the (convex, stretched) sphere.
    std::vector<float> surface(floats);
    ASSERT_EQ(segmorph_decoder_surface_normals(decoder, nullptr, surface.data(), floats), SEGMORPH_STATUS_OK);
    for (size_t v = 0; v < floats / 3; ++v) {
      const float* n = &surface[v * 3];
      ASSERT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0, 1e-6) << c.name << " vertex " << v;
      EXPECT_GT(n[0] * c.base[v * 3] + n[1] * c.base[v * 3 + 1] + n[2] * c.base[v * 3 + 2], 0) << c.name;
    }
    // Authored normals (here: the surface's, tilted) come back from the base mesh itself as they were, normalized.
    std::vector<float> authored(floats);
    for (size_t i = 0; i < floats; ++i) authored[i] = surface[i] + (i % 3 == 2 ? 0.3f : 0.0f);
    const std::vector<float> turned_base = rotated(c.base, 0.0), turned_frame = rotated(c.base, 0.7);
    std::vector<float> shapes = turned_base;
    shapes.insert(shapes.end(), turned_frame.begin(), turned_frame.end());
    std::vector<float> out(2 * floats);
    ASSERT_EQ(segmorph_decoder_turn_normals(decoder, authored.data(), shapes.data(), 2, out.data(), out.size()),
              SEGMORPH_STATUS_OK);
    std::vector<float> unit(floats);
    for (size_t v = 0; v < floats / 3; ++v) {
      const float* a = &authored[v * 3];
      const double length = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
      for (int k = 0; k < 3; ++k) unit[v * 3 + size_t(k)] = float(a[k] / length);
    }
    // Rotated, the surface normal a becomes R a, and a normal turned by the smallest rotation taking a to R a keeps its
    // angle to it (it is R n only where n and a lie in a plane across the axis).
    const std::vector<float> surface_now = rotated(surface, 0.7);
    for (size_t i = 0; i < floats; ++i) ASSERT_NEAR(out[i], unit[i], 1e-6) << c.name << " float " << i;
    for (size_t v = 0; v < floats / 3; ++v) {
      const float *n = &unit[v * 3], *a = &surface[v * 3], *m = &out[floats + v * 3], *b = &surface_now[v * 3];
      ASSERT_NEAR(m[0] * b[0] + m[1] * b[1] + m[2] * b[2], n[0] * a[0] + n[1] * a[1] + n[2] * a[2], 1e-5)
          << c.name << " vertex " << v;
    }
    // The surface's own normals turn to the rotated surface's.
    ASSERT_EQ(segmorph_decoder_turn_normals(decoder, surface.data(), turned_frame.data(), 1, out.data(), floats),
              SEGMORPH_STATUS_OK);
    for (size_t i = 0; i < floats; ++i) ASSERT_NEAR(out[i], surface_now[i], 1e-5) << c.name << " float " << i;
    // Decoded frames: the C++ API gives the C API's floats.
    std::vector<float> frames(segmorph_decode_clip_bound(decoder, 0)), normals(frames.size());
    ASSERT_EQ(segmorph_decode_clip(decoder, 0, frames.data(), frames.size()), SEGMORPH_STATUS_OK);
    const size_t count = segmorph_decoder_frame_count(decoder, 0);
    ASSERT_EQ(segmorph_decoder_turn_normals(decoder, surface.data(), frames.data(), count, normals.data(),
                                            normals.size()),
              SEGMORPH_STATUS_OK);
    AnimationDecoder api;
    ASSERT_TRUE(api.open(c.stream.data(), c.stream.size(), c.base.data(), floats / 3, c.clips[0].triangles.data(),
                         c.clips[0].triangles.size())
                    .ok());
    std::vector<float> again(normals.size());
    ASSERT_TRUE(api.turn_normals(surface.data(), frames.data(), count, again.data(), again.size()).ok());
    EXPECT_TRUE(same_bits(again.data(), normals.data(), normals.size())) << c.name;
    segmorph_decoder_destroy(decoder);
  }
}

TEST(DecoderApi, NormalsRefuseBadArguments) {
  const Case c = cases()[0];
  const size_t floats = c.base.size();
  std::vector<float> normals(floats, 0.5f), out(2 * floats);
  segmorph_decoder* decoder = segmorph_decoder_create();
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, normals.data(), c.base.data(), 1, out.data(), out.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);  // nothing open
  EXPECT_EQ(segmorph_decoder_surface_normals(decoder, nullptr, out.data(), out.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, nullptr, c.base.data(), 1, out.data(), out.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, normals.data(), nullptr, 1, out.data(), out.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, normals.data(), c.base.data(), 1, nullptr, out.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, normals.data(), c.base.data(), 2, out.data(), floats),
            SEGMORPH_STATUS_INVALID_ARGUMENT);  // room for one frame, two asked
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, normals.data(), c.base.data(), SIZE_MAX / 2, out.data(), out.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);  // a count whose size overflows
  expect_one_line(segmorph_decoder_message(decoder));
  EXPECT_EQ(segmorph_decoder_surface_normals(decoder, nullptr, out.data(), floats - 1),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, normals.data(), c.base.data(), 0, nullptr, 0), SEGMORPH_STATUS_OK);
  EXPECT_EQ(segmorph_decoder_turn_normals(decoder, normals.data(), c.base.data(), 1, out.data(), floats),
            SEGMORPH_STATUS_OK);
  segmorph_decoder_destroy(decoder);
}

TEST(DecoderApi, BadArgumentsAreRefusedWithAMessage) {
  const Case c = cases()[1];
  const std::vector<uint32_t>& triangles = c.clips[0].triangles;
  const size_t vertices = c.base.size() / 3;
  EXPECT_EQ(segmorph_decoder_open(nullptr, c.stream.data(), c.stream.size(), c.base.data(), vertices,
                                  triangles.data(), triangles.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  segmorph_decoder* decoder = segmorph_decoder_create();
  auto expect_invalid = [&](segmorph_status status, const char* what) {
    EXPECT_EQ(status, SEGMORPH_STATUS_INVALID_ARGUMENT) << what;
    expect_one_line(segmorph_decoder_message(decoder));
  };
  expect_invalid(segmorph_decoder_open(decoder, nullptr, c.stream.size(), c.base.data(), vertices, triangles.data(),
                                       triangles.size()),
                 "null stream");
  expect_invalid(segmorph_decoder_open(decoder, c.stream.data(), c.stream.size(), nullptr, vertices, triangles.data(),
                                       triangles.size()),
                 "null positions");
  expect_invalid(segmorph_decoder_open(decoder, c.stream.data(), c.stream.size(), c.base.data(), vertices, nullptr,
                                       triangles.size()),
                 "null indices");
  expect_invalid(segmorph_decoder_open(decoder, c.stream.data(), c.stream.size(), c.base.data(), vertices,
                                       triangles.data(), triangles.size() - 1),
                 "indices not triangles");
  std::vector<uint32_t> out_of_range = triangles;
  out_of_range[7] = uint32_t(vertices);
  expect_invalid(segmorph_decoder_open(decoder, c.stream.data(), c.stream.size(), c.base.data(), vertices,
                                       out_of_range.data(), out_of_range.size()),
                 "index out of range");
  // Nothing open: every call refuses, queries say 0.
  std::vector<float> frames(1000);
  expect_invalid(segmorph_decode_clip(decoder, 0, frames.data(), frames.size()), "closed: decode_clip");
  expect_invalid(segmorph_decode_frame(decoder, frames.data(), frames.size()), "closed: decode_frame");
  expect_invalid(segmorph_decoder_seek(decoder, 0), "closed: seek");
  EXPECT_EQ(segmorph_decoder_clip_count(decoder), 0u);
  EXPECT_EQ(segmorph_decode_clip_bound(decoder, 0), 0u);

  ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK);
  const size_t floats = segmorph_decode_clip_bound(decoder, 0);
  frames.assign(floats, 0.0f);
  expect_invalid(segmorph_decode_clip(decoder, 0, frames.data(), floats - 1), "destination too small");
  expect_invalid(segmorph_decode_clip(decoder, 0, nullptr, floats), "null destination");
  expect_invalid(segmorph_decode_clip(decoder, 3, frames.data(), floats), "no such clip");
  expect_invalid(segmorph_decoder_seek(decoder, 3), "seek to no such clip");
  expect_invalid(segmorph_decode_frame(decoder, frames.data(), vertices * 3 - 1), "frame destination too small");
  EXPECT_EQ(segmorph_decode_clip_bound(decoder, 3), 0u);
  EXPECT_EQ(segmorph_decoder_frame_count(decoder, 3), 0u);
  // Still usable after the refusals.
  EXPECT_EQ(segmorph_decode_clip(decoder, 0, frames.data(), floats), SEGMORPH_STATUS_OK);
  EXPECT_TRUE(same_bits(frames.data(), reference(c)[0].positions.data(), floats));
  segmorph_decoder_destroy(decoder);
  segmorph_decoder_destroy(nullptr);
  EXPECT_STREQ(segmorph_status_name(SEGMORPH_STATUS_BAD_DATA), "bad data");
  EXPECT_EQ(segmorph_version(), SEGMORPH_VERSION);
}

TEST(DecoderApi, DamagedStreamsAreBadDataAndTheDecoderIsReusable) {
  const std::vector<Case> all = cases();
  segmorph_decoder* decoder = segmorph_decoder_create();
  std::mt19937 random(7);
  for (const Case& c : all) {
    const std::vector<FrameSequence> expected = reference(c);
    const size_t vertices = c.base.size() / 3;
    const std::vector<uint32_t>& triangles = c.clips[0].triangles;
    std::vector<float> frames;
    // Decodes every clip of `bytes`: the first failure's status, or ok.
    auto decode_all = [&](const std::vector<uint8_t>& bytes) {
      segmorph_status status = segmorph_decoder_open(decoder, bytes.data(), bytes.size(), c.base.data(), vertices,
                                                     triangles.data(), triangles.size());
      for (size_t clip = 0; status == SEGMORPH_STATUS_OK && clip < segmorph_decoder_clip_count(decoder); ++clip) {
        frames.resize(segmorph_decode_clip_bound(decoder, clip));
        status = segmorph_decode_clip(decoder, clip, frames.data(), frames.size());
      }
      return status;
    };
    for (size_t size = 0; size < c.stream.size(); size += 1 + size / 8) {
      const std::vector<uint8_t> prefix(c.stream.begin(), c.stream.begin() + long(size));
      EXPECT_EQ(decode_all(prefix), SEGMORPH_STATUS_BAD_DATA) << c.name << ": prefix of " << size << " bytes";
      expect_one_line(segmorph_decoder_message(decoder));
    }
    std::vector<uint8_t> longer = c.stream;
    longer.push_back(0);
    EXPECT_EQ(decode_all(longer), SEGMORPH_STATUS_BAD_DATA) << c.name << ": a trailing byte";
    for (int flip = 0; flip < 200; ++flip) {
      std::vector<uint8_t> damaged = c.stream;
      damaged[random() % damaged.size()] ^= uint8_t(1u << (random() % 8));
      const segmorph_status status = decode_all(damaged);
      EXPECT_TRUE(status == SEGMORPH_STATUS_OK || status == SEGMORPH_STATUS_BAD_DATA ||
                  status == SEGMORPH_STATUS_UNSUPPORTED)
          << c.name << ": " << segmorph_status_name(status);
      if (status != SEGMORPH_STATUS_OK) expect_one_line(segmorph_decoder_message(decoder));
    }
    std::vector<uint8_t> newer = c.stream;
    newer[4] = SEGMORPH_STREAM_VERSION_MAX + 1;
    EXPECT_EQ(decode_all(newer), SEGMORPH_STATUS_UNSUPPORTED);
    // The same decoder, the intact stream: the reference frames.
    ASSERT_EQ(decode_all(c.stream), SEGMORPH_STATUS_OK) << segmorph_decoder_message(decoder);
    EXPECT_TRUE(same_bits(frames.data(), expected.back().positions.data(), frames.size())) << c.name;
  }
  segmorph_decoder_destroy(decoder);
}

// A decoder's own threads (set_threads; version-4 frames split over them, the other versions on the calling thread)
// give the same floats for any count, through both APIs, after frames decoded one at a time and seeks, and for
// kept targets.
TEST(DecoderApi, ItsThreadsGiveTheReferenceFrames) {
  for (const Case& c : cases()) {
    const std::vector<FrameSequence> expected = reference(c);
    for (size_t threads : {size_t(0), size_t(2), size_t(3), size_t(64)}) {
      SCOPED_TRACE(c.name + ", threads " + std::to_string(threads));
      segmorph_decoder* decoder = segmorph_decoder_create();
      ASSERT_EQ(segmorph_decoder_set_threads(decoder, threads), SEGMORPH_STATUS_OK);
      ASSERT_EQ(open(decoder, c), SEGMORPH_STATUS_OK) << segmorph_decoder_message(decoder);
      std::vector<float> frame(c.base.size());
      ASSERT_EQ(segmorph_decode_frame(decoder, frame.data(), frame.size()), SEGMORPH_STATUS_OK);
      for (size_t clip = expected.size(); clip-- > 0;) {
        std::vector<float> frames(segmorph_decode_clip_bound(decoder, clip), -1.0f);
        ASSERT_EQ(segmorph_decode_clip(decoder, clip, frames.data(), frames.size()), SEGMORPH_STATUS_OK)
            << segmorph_decoder_message(decoder);
        EXPECT_TRUE(same_bits(frames.data(), expected[clip].positions.data(), frames.size())) << "clip " << clip;
      }
      segmorph_decoder_destroy(decoder);

      AnimationDecoder animation;
      animation.set_threads(threads);
      EXPECT_EQ(animation.threads(), threads);
      ASSERT_TRUE(animation.open(c.stream.data(), c.stream.size(), c.base.data(), c.base.size() / 3,
                                 c.clips[0].triangles.data(), c.clips[0].triangles.size())
                      .ok());
      std::vector<float> frames(animation.clip_floats(0));
      ASSERT_TRUE(animation.decode_clip(0, frames.data(), frames.size()).ok());
      EXPECT_TRUE(same_bits(frames.data(), expected[0].positions.data(), frames.size()));
    }
  }
}

// No global state: decoders on several threads at once, each its own stream, give each stream's frames.
TEST(DecoderApi, DecodersOnSeveralThreadsGiveTheReferenceFrames) {
  const std::vector<Case> all = cases();
  std::vector<std::vector<FrameSequence>> expected;
  for (const Case& c : all) expected.push_back(reference(c));
  std::vector<int> same(all.size() * 2, 0);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < same.size(); ++t)
    threads.emplace_back([&, t] {
      const Case& c = all[t % all.size()];
      segmorph_decoder* decoder = segmorph_decoder_create();
      bool ok = open(decoder, c) == SEGMORPH_STATUS_OK;
      for (size_t clip = 0; ok && clip < expected[t % all.size()].size(); ++clip) {
        std::vector<float> frames(segmorph_decode_clip_bound(decoder, clip));
        ok = segmorph_decode_clip(decoder, clip, frames.data(), frames.size()) == SEGMORPH_STATUS_OK &&
             same_bits(frames.data(), expected[t % all.size()][clip].positions.data(), frames.size());
      }
      segmorph_decoder_destroy(decoder);
      same[t] = ok ? 1 : 0;
    });
  for (std::thread& thread : threads) thread.join();
  for (size_t t = 0; t < same.size(); ++t) EXPECT_EQ(same[t], 1) << "thread " << t << ": " << all[t % all.size()].name;
}

// A base mesh with another vertex count than the stream's is the wrong mesh.
TEST(DecoderApi, AStreamForAnotherMeshIsBadData) {
  const Case c = cases()[0];
  std::vector<float> smaller(c.base.begin(), c.base.end() - 3);
  std::vector<uint32_t> triangles;
  for (size_t t = 0; t + 2 < c.clips[0].triangles.size(); t += 3)
    if (std::max({c.clips[0].triangles[t], c.clips[0].triangles[t + 1], c.clips[0].triangles[t + 2]}) <
        smaller.size() / 3)
      triangles.insert(triangles.end(), c.clips[0].triangles.begin() + long(t), c.clips[0].triangles.begin() + long(t) + 3);
  AnimationDecoder decoder;
  const Status status = decoder.open(c.stream.data(), c.stream.size(), smaller.data(), smaller.size() / 3,
                                     triangles.data(), triangles.size());
  EXPECT_EQ(status.code(), StatusCode::bad_data);
  EXPECT_NE(status.message().find("vertices"), std::string::npos) << status.message();
  EXPECT_FALSE(decoder.is_open());
}

// A small track set through the C API: the values decode_tracks gives, in the documented order.
TEST(DecoderApi, TrackStreamsDecodeInLayoutOrder) {
  TrackSet tracks;
  tracks.times = {{0.0f, 0.5f, 1.0f, 1.5f}, {0.25f, 2.0f}};
  tracks.samplers.push_back({TrackPath::translation, 3, 0, {0, 0, 0, 1, 0, 0, 2, 1, 0, 3, 1, 1}});
  tracks.samplers.push_back({TrackPath::rotation, 4, 1, {0, 0, 0, 1, 0, 0.6f, 0, 0.8f}});
  tracks.samplers.push_back({TrackPath::weights, 2, 1, {0, 1, 0.5f, 0.25f}});
  std::vector<uint8_t> bytes;
  TrackSet decoded;
  ASSERT_TRUE(encode_tracks(tracks, {1e-3, 1e-4, 1e-3}, bytes, decoded).ok());
  const size_t time_counts[] = {4, 2};
  const segmorph_track_sampler samplers[] = {{0, 0, 3}, {1, 1, 4}, {1, 3, 2}};
  const size_t floats = segmorph_decode_tracks_bound(time_counts, 2, samplers, 3);
  ASSERT_EQ(floats, 4u + 2u + 12u + 8u + 4u);
  std::vector<float> expected;
  for (const std::vector<float>& keys : decoded.times) expected.insert(expected.end(), keys.begin(), keys.end());
  for (const TrackSampler& sampler : decoded.samplers)
    expected.insert(expected.end(), sampler.values.begin(), sampler.values.end());
  segmorph_decoder* decoder = segmorph_decoder_create();
  std::vector<float> out(floats);
  ASSERT_EQ(segmorph_decode_tracks(decoder, bytes.data(), bytes.size(), time_counts, 2, samplers, 3, out.data(),
                                   out.size()),
            SEGMORPH_STATUS_OK)
      << segmorph_decoder_message(decoder);
  EXPECT_TRUE(same_bits(out.data(), expected.data(), floats));

  // Layouts that are invalid, or that disagree with the stream.
  const segmorph_track_sampler bad_path[] = {{0, 4, 3}}, bad_components[] = {{0, 1, 3}}, bad_times[] = {{2, 0, 3}},
                               no_weights[] = {{0, 3, 0}};
  EXPECT_EQ(segmorph_decode_tracks_bound(time_counts, 1, bad_path, 1), 0u);
  EXPECT_EQ(segmorph_decode_tracks_bound(time_counts, 1, bad_components, 1), 0u);
  EXPECT_EQ(segmorph_decode_tracks_bound(time_counts, 2, bad_times, 1), 0u);
  EXPECT_EQ(segmorph_decode_tracks_bound(time_counts, 1, no_weights, 1), 0u);
  EXPECT_EQ(segmorph_decode_tracks_bound(time_counts, 2, samplers, 1), 0u) << "time array 1 used by no sampler";
  EXPECT_EQ(segmorph_decode_tracks(decoder, bytes.data(), bytes.size(), time_counts, 1, bad_path, 1, out.data(),
                                   out.size()),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  expect_one_line(segmorph_decoder_message(decoder));
  const segmorph_track_sampler other[] = {{0, 0, 3}, {1, 2, 3}, {1, 3, 2}};
  EXPECT_EQ(segmorph_decode_tracks(decoder, bytes.data(), bytes.size(), time_counts, 2, other, 3, out.data(),
                                   out.size()),
            SEGMORPH_STATUS_BAD_DATA);
  expect_one_line(segmorph_decoder_message(decoder));
  EXPECT_EQ(segmorph_decode_tracks(decoder, bytes.data(), bytes.size(), time_counts, 2, samplers, 3, out.data(),
                                   floats - 1),
            SEGMORPH_STATUS_INVALID_ARGUMENT);
  // A layout claiming more keys than the stream's bytes can hold is refused before anything is allocated.
  const size_t huge[] = {size_t(1) << 20};
  const segmorph_track_sampler one[] = {{0, 0, 3}};
  EXPECT_EQ(segmorph_decode_tracks(decoder, bytes.data(), bytes.size(), huge, 1, one, 1, out.data(), out.size()),
            SEGMORPH_STATUS_BAD_DATA);
  EXPECT_NE(std::string(segmorph_decoder_message(decoder)).find("more values"), std::string::npos);
  segmorph_decoder_destroy(decoder);
}

}  // namespace
}  // namespace segmorph
