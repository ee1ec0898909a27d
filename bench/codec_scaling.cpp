// How the codec's time and memory grow with the vertex count V and the frame count F, on a synthetic sequence
// built in memory: a torus of about V vertices (a regular grid of rings, one connected closed surface) whose
// ring and tube radii swell in travelling waves while it bends, twists and drifts: smooth, non-rigid motion
// that looks the same at every resolution, so only V and F change between runs.
//   codec_scaling --vertices V --frames F [--error E | --bpvf R] [--threads N]
//   codec_scaling --vertices V --frames F --write-cache PREFIX
// One run measures one (V, F) point and prints one JSON object on stdout:
//   vertices, frames, threads (the setting: 0 is every core), triangles, input_mb (the frames, V × F × 3 floats),
//   clusters, stream_bytes, bpvf (the stream's), kg_percent (decoded against the input), milliseconds {generate,
//   draco, segmentation, motion, prediction, rate_control, entropy, encode (the whole encode_animation), decode, copy
//   (the restored frames copied once: the practical limit of a decoder)} and peak_rss_kb {input, encode, decode}:
//   the process's peak resident set after building the frames, and during the encoder and the decoder (the peak is
//   reset before each where Linux allows it, /proc/self/clear_refs; peak_reset says whether it did).
// The base mesh is Draco's (edgebreaker, 14 bits, timed with the decoding and vertex matching the container
// does); the codec encodes against the stand-in base of the other bench tools so that it sees V vertices in
// the generator's order. Run one point per process: the peak resident set only grows.
// With --write-cache, nothing is measured: the sequence is written as PREFIX.obj (frame 0 and the triangles) and
// PREFIX.pc2 (every frame, 30 fps), a vertex cache segmorph reads (docs/caches.md) and bakes into the glTF of
// one-hot morph targets the harness measures whole files on (bench/lib/large.mjs).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <string>

#include "decode/frame_decoder.h"
#include "draco_base_mesh.h"
#include "encode/encoder.h"
#include "encode/metrics.h"
#include "stand_in_base.h"

using namespace segmorph;

namespace {

using Clock = std::chrono::steady_clock;
double milliseconds_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// The process's peak resident set in KB (VmHWM), 0 when /proc is not there.
long peak_rss_kb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atol(line.c_str() + 6);
  return 0;
}

// Resets VmHWM to the current resident set (Linux: "5" > /proc/self/clear_refs); false where not allowed.
bool reset_peak_rss() {
  std::FILE* file = std::fopen("/proc/self/clear_refs", "w");
  if (!file) return false;
  const bool ok = std::fputs("5", file) >= 0;
  return std::fclose(file) == 0 && ok;
}

// The torus: `rings` rings of `sides` vertices each, V = rings × sides, 2V triangles.
struct Torus {
  size_t rings = 0, sides = 0;
  size_t vertex_count() const { return rings * sides; }
};

Torus torus_near(size_t vertices) {
  Torus torus;
  torus.sides = std::max<size_t>(3, size_t(std::lround(std::sqrt(double(vertices) / 2.0))));
  torus.rings = std::max<size_t>(3, size_t(std::lround(double(vertices) / double(torus.sides))));
  return torus;
}

std::vector<uint32_t> torus_triangles(const Torus& torus) {
  std::vector<uint32_t> triangles;
  triangles.reserve(torus.vertex_count() * 6);
  for (size_t i = 0; i < torus.rings; ++i)
    for (size_t j = 0; j < torus.sides; ++j) {
      const auto at = [&](size_t a, size_t b) { return uint32_t((a % torus.rings) * torus.sides + b % torus.sides); };
      const uint32_t q[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      for (uint32_t v : {q[0], q[1], q[2], q[0], q[2], q[3]}) triangles.push_back(v);
    }
  return triangles;
}

// Frame f of F: angles u around the ring, v around the tube; phase one period over the clip.
FrameSequence torus_frames(const Torus& torus, size_t frame_count) {
  const double pi = 3.14159265358979323846;
  FrameSequence clip;
  clip.vertex_count = torus.vertex_count();
  clip.frame_count = frame_count;
  clip.triangles = torus_triangles(torus);
  clip.positions.resize(clip.vertex_count * frame_count * 3);
  for (size_t f = 0; f < frame_count; ++f) {
    clip.times.push_back(float(f) / 30.0f);
    const double phase = 2 * pi * double(f) / double(frame_count);
    float* out = clip.frame(f);
    for (size_t i = 0; i < torus.rings; ++i) {
      const double u = 2 * pi * double(i) / double(torus.rings);
      const double ring = 1.0 + 0.1 * std::sin(2 * u + phase);               // the ring breathes
      const double tube = 0.3 * (1.0 + 0.25 * std::sin(3 * u - 2 * phase));  // a wave runs along the tube
      const double bend = 0.35 * std::sin(phase) * std::cos(u);              // the ring folds like a saddle
      const double twist = 0.4 * std::sin(phase + u);                        // and twists its tube
      for (size_t j = 0; j < torus.sides; ++j) {
        const double v = 2 * pi * double(j) / double(torus.sides) + twist;
        const double radius = ring + tube * std::cos(v);
        const double x = radius * std::cos(u), y = radius * std::sin(u);
        const double z = tube * std::sin(v) + bend * std::cos(u) * radius;
        float* p = out + (i * torus.sides + j) * 3;
        p[0] = float(x + 0.3 * double(f) / double(frame_count));  // and drifts
        p[1] = float(y);
        p[2] = float(z);
      }
    }
  }
  return clip;
}

// Writes `clip` as PREFIX.obj and PREFIX.pc2; false with a message on a failed write.
bool write_cache(const FrameSequence& clip, const std::string& prefix) {
  std::FILE* obj = std::fopen((prefix + ".obj").c_str(), "wb");
  if (!obj) return false;
  bool ok = true;
  for (size_t v = 0; v < clip.vertex_count; ++v) {
    const float* p = clip.frame(0) + v * 3;
    ok = ok && std::fprintf(obj, "v %.9g %.9g %.9g\n", p[0], p[1], p[2]) > 0;
  }
  for (size_t t = 0; t < clip.triangle_count(); ++t)
    ok = ok && std::fprintf(obj, "f %u %u %u\n", clip.triangles[t * 3] + 1, clip.triangles[t * 3 + 1] + 1,
                            clip.triangles[t * 3 + 2] + 1) > 0;
  ok = std::fclose(obj) == 0 && ok;
  std::FILE* pc2 = std::fopen((prefix + ".pc2").c_str(), "wb");
  if (!pc2) return false;
  // PC2: "POINTCACHE2\0", version 1, points, start frame, sample rate (frames per sample), samples; then the points.
  const int32_t version = 1, points = int32_t(clip.vertex_count), samples = int32_t(clip.frame_count);
  const float start = 0, rate = 1;
  ok = std::fwrite("POINTCACHE2", 1, 12, pc2) == 12 && ok;
  for (const void* field : {static_cast<const void*>(&version), static_cast<const void*>(&points)})
    ok = std::fwrite(field, 4, 1, pc2) == 1 && ok;
  for (const void* field : {static_cast<const void*>(&start), static_cast<const void*>(&rate)})
    ok = std::fwrite(field, 4, 1, pc2) == 1 && ok;
  ok = std::fwrite(&samples, 4, 1, pc2) == 1 && ok;
  ok = std::fwrite(clip.positions.data(), sizeof(float), clip.positions.size(), pc2) == clip.positions.size() && ok;
  return std::fclose(pc2) == 0 && ok;
}

}  // namespace

int main(int argc, char** argv) {
  size_t vertices = 0, frames = 0;
  std::string cache;
  CodecSettings settings;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (i + 1 < argc && arg == "--vertices")
      vertices = size_t(std::atol(argv[++i]));
    else if (i + 1 < argc && arg == "--frames")
      frames = size_t(std::atol(argv[++i]));
    else if (i + 1 < argc && arg == "--error")
      settings.mode = RateMode::error, settings.target = std::atof(argv[++i]);
    else if (i + 1 < argc && arg == "--bpvf")
      settings.mode = RateMode::bpvf, settings.target = std::atof(argv[++i]);
    else if (i + 1 < argc && arg == "--threads" && std::atol(argv[i + 1]) >= 0)  // 0: every core; default 1
      settings.threads = size_t(std::atol(argv[++i]));
    else if (i + 1 < argc && arg == "--write-cache")
      cache = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: codec_scaling --vertices V --frames F [--error E | --bpvf R | --write-cache PREFIX] "
                   "[--threads N]\n");
      return 2;
    }
  }
  if (vertices < 9 || frames < 2 || !(settings.target > 0)) {
    std::fprintf(stderr, "codec_scaling: needs --vertices 9 or more, --frames 2 or more and a positive target\n");
    return 2;
  }

  auto start = Clock::now();
  const Torus torus = torus_near(vertices);
  std::vector<FrameSequence> clips{torus_frames(torus, frames)};
  const double generate_ms = milliseconds_since(start);
  const FrameSequence& clip = clips[0];
  const long input_kb = peak_rss_kb();
  if (!cache.empty()) {
    if (write_cache(clip, cache)) return 0;
    std::fprintf(stderr, "codec_scaling: cannot write %s.obj and %s.pc2\n", cache.c_str(), cache.c_str());
    return 1;
  }

  // The container's base mesh work: Draco encoding, decoding, and the map from decoded to original vertices.
  bool peak_reset = reset_peak_rss();
  start = Clock::now();
  BaseMesh base_mesh;
  base_mesh.vertex_count = clip.vertex_count;
  base_mesh.triangles = clip.triangles;
  base_mesh.attributes.push_back(
      {"POSITION", 3, std::vector<float>(clip.frame(0), clip.frame(0) + clip.vertex_count * 3)});
  DracoSettings draco;
  std::vector<uint8_t> draco_bytes;
  std::map<std::string, int> attribute_ids;
  BaseMesh decoded_base;
  std::vector<uint32_t> source;
  Status status = encode_draco_base_mesh(base_mesh, draco, draco_bytes, attribute_ids);
  if (status.ok()) status = decode_draco_base_mesh(draco_bytes.data(), draco_bytes.size(), attribute_ids, decoded_base);
  if (status.ok()) status = match_decoded_vertices(base_mesh, decoded_base, draco, source);
  const double draco_ms = milliseconds_since(start);
  if (!status.ok()) {
    std::fprintf(stderr, "codec_scaling: Draco base mesh: %s\n", status.message().c_str());
    return 1;
  }
  base_mesh = BaseMesh();
  decoded_base = BaseMesh();

  const std::vector<float> base = bench::stand_in_base(clip);
  std::vector<uint8_t> stream;
  StreamReport report;
  start = Clock::now();
  status = encode_animation(clips, base, settings, stream, &report);
  const double encode_ms = milliseconds_since(start);
  const long encode_kb = peak_rss_kb();
  if (!status.ok()) {
    std::fprintf(stderr, "codec_scaling: encode: %s\n", status.message().c_str());
    return 1;
  }

  peak_reset = reset_peak_rss() && peak_reset;
  std::vector<FrameSequence> decoded;
  start = Clock::now();
  status = decode_animation(stream.data(), stream.size(), base, clip.triangles, decoded, settings.threads);
  const double decode_ms = milliseconds_since(start);
  const long decode_kb = peak_rss_kb();
  if (!status.ok() || decoded.size() != 1) {
    std::fprintf(stderr, "codec_scaling: decode: %s\n", status.ok() ? "no clip" : status.message().c_str());
    return 1;
  }
  // The practical limit of a decoder: writing the restored frames once.
  std::vector<float> copy(decoded[0].positions.size());
  start = Clock::now();
  std::memcpy(copy.data(), decoded[0].positions.data(), copy.size() * sizeof(float));
  const double copy_ms = milliseconds_since(start);
  const volatile float sink = copy[copy.size() / 2];
  (void)sink;

  ErrorAccumulator accumulator;
  accumulator.add(clip, decoded[0]);
  const ErrorMetrics metrics = accumulator.result();
  std::printf(
      "{\"vertices\":%zu,\"frames\":%zu,\"threads\":%zu,\"triangles\":%zu,\"input_mb\":%.1f,\"clusters\":%zu,"
      "\"stream_bytes\":%zu,\"bpvf\":%.4f,\"kg_percent\":%.6g,\"milliseconds\":{\"generate\":%.1f,\"draco\":%.1f,"
      "\"segmentation\":%.1f,\"motion\":%.1f,\"prediction\":%.1f,\"rate_control\":%.1f,\"entropy\":%.1f,\"encode\":%.1f,\"decode\":%.1f,"
      "\"copy\":%.2f},\"peak_rss_kb\":{\"input\":%ld,\"encode\":%ld,\"decode\":%ld},\"peak_reset\":%s}\n",
      clip.vertex_count, frames, settings.threads, clip.triangle_count(),
      double(clip.positions.size() * sizeof(float)) / 1e6,
      report.clusters, stream.size(), bits_per_vertex_frame(stream.size(), clip.vertex_count, frames),
      metrics.kg_percent, generate_ms, draco_ms, report.ms_segmentation, report.ms_motion, report.ms_prediction,
      report.ms_rate_control, report.ms_entropy, encode_ms, decode_ms, copy_ms, input_kb, encode_kb, decode_kb,
      peak_reset ? "true" : "false");
  return 0;
}
