// Small synthetic meshes for the codec's tests, and the helpers its tests share.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <vector>

#include <gtest/gtest.h>

#include "common/frame_sequence.h"
#include "encode/encoder.h"
#include "encode/metrics.h"

namespace segmorph::testing {

// A triangle mesh in double precision, as the spectral stages take it.
struct Mesh {
  std::vector<double> positions;    // W × 3
  std::vector<uint32_t> triangles;  // T × 3
  size_t vertex_count() const { return positions.size() / 3; }
};

// A unit icosphere subdivided `levels` times (10 · 4^levels + 2 vertices), stretched by `stretch` along x.
inline FrameSequence stretched_sphere(int levels, double stretch) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<std::array<double, 3>> points = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                               {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<uint32_t, 3>> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                                {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                                {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                                {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : points) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (double& c : p) c /= n;
  }
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> middle;
    auto split = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      std::array<double, 3> m;
      for (int c = 0; c < 3; ++c) m[size_t(c)] = points[a][size_t(c)] + points[b][size_t(c)];
      const double n = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
      for (double& c : m) c /= n;
      points.push_back(m);
      return middle[key] = uint32_t(points.size() - 1);
    };
    std::vector<std::array<uint32_t, 3>> finer;
    for (const auto& f : faces) {
      const uint32_t ab = split(f[0], f[1]), bc = split(f[1], f[2]), ca = split(f[2], f[0]);
      finer.insert(finer.end(), {{f[0], ab, ca}, {f[1], bc, ab}, {f[2], ca, bc}, {ab, bc, ca}});
    }
    faces.swap(finer);
  }
  FrameSequence clip;
  clip.vertex_count = points.size();
  clip.frame_count = 1;
  for (const auto& p : points) clip.positions.insert(clip.positions.end(), {float(p[0] * stretch), float(p[1]), float(p[2])});
  for (const auto& f : faces) clip.triangles.insert(clip.triangles.end(), {f[0], f[1], f[2]});
  return clip;
}

// An n × n grid of unit squares over [0, n]² at height z = height(i, j), two triangles per square, wound
// counter-clockwise seen from +z; squares whose lower-left corner (i, j) satisfies hole(i, j) are left out.
template <typename Height, typename Hole>
FrameSequence height_field(int n, Height height, Hole hole) {
  FrameSequence clip;
  clip.vertex_count = size_t((n + 1) * (n + 1));
  clip.frame_count = 1;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) clip.positions.insert(clip.positions.end(), {float(i), float(j), float(height(i, j))});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (hole(i, j)) continue;
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
      clip.triangles.insert(clip.triangles.end(), {a, b, d, a, d, c});
    }
  return clip;
}

template <typename Height>
FrameSequence height_field(int n, Height height) {
  return height_field(n, height, [](int, int) { return false; });
}

// A stretched sphere (642 vertices, x in [−2, 2]) whose right half bends about z by up to `bend` radians,
// with a travelling ripple: a smooth, non-rigid animation of `frames` frames.
inline FrameSequence bending_clip(size_t frames, double bend, double phase) {
  const FrameSequence shape = testing::stretched_sphere(3, 2.0);
  FrameSequence clip = shape;
  clip.frame_count = frames;
  clip.positions.clear();
  for (size_t f = 0; f < frames; ++f) {
    const double t = double(f) / double(frames);
    for (size_t v = 0; v < shape.vertex_count; ++v) {
      const double x = shape.positions[v * 3], y = shape.positions[v * 3 + 1], z = shape.positions[v * 3 + 2];
      const double angle = x > 0 ? bend * t * x / 2 : 0.0;
      const double ripple = 0.02 * std::sin(3 * x + 6.28 * t + phase);
      clip.positions.insert(clip.positions.end(),
                            {float(x * std::cos(angle) - y * std::sin(angle)),
                             float(x * std::sin(angle) + y * std::cos(angle) + ripple), float(z)});
    }
    clip.times.push_back(float(f) / 30);
  }
  return clip;
}

// The base as a decoder would have it: the first frame on a grid of 1e-4 (as a 14-bit Draco quantization of a
// shape a few units across).
inline std::vector<float> quantized_base(const FrameSequence& clip) {
  std::vector<float> base(clip.frame(0), clip.frame(0) + clip.vertex_count * 3);
  for (float& x : base) x = float(std::round(x / 1e-4) * 1e-4);
  return base;
}

// The KG error (%) of decoded clips against the originals.
inline double kg(const std::vector<FrameSequence>& original, const std::vector<FrameSequence>& decoded) {
  ErrorAccumulator accumulator;
  for (size_t c = 0; c < original.size(); ++c) accumulator.add(original[c], decoded[c]);
  return accumulator.result().kg_percent;
}

// An encode that is expected to succeed: the stream, the encoder's report and its own reconstruction.
struct Encoded {
  std::vector<uint8_t> stream;
  StreamReport report;
  std::vector<FrameSequence> reconstruction;
};

inline Encoded encode(const std::vector<FrameSequence>& clips, const std::vector<float>& base,
                      const CodecSettings& settings) {
  Encoded encoded;
  const Status status =
      encode_animation(clips, base, settings, encoded.stream, &encoded.report, &encoded.reconstruction);
  EXPECT_TRUE(status.ok()) << status.message();
  return encoded;
}

}  // namespace segmorph::testing
