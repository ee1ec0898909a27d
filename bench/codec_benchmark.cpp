// Google Benchmark of the codec's stages on one sequence (Release build, one core):
//   codec_benchmark [FILE] [--error E] [--fast-decode] [--benchmark_filter=...] [other Google Benchmark flags]
// FILE defaults to the cow sequence in ../shared/samples. The stream is encoded once at startup (at --error E,
// default 0.15; with --fast-decode its residuals in the table code, CodecSettings::table_residuals); the decoder
// benchmarks decode it, the encoder's stage benchmarks rerun one stage on the encoder's own intermediate data.
// Counters: vertex-frames per second (vf/s) where it means something.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "common/reconstruction.h"
#include "common/stream.h"
#include "common/topology.h"
#include "decode/frame_decoder.h"
#include "decode/stream_reader.h"
#include "encode/encoder.h"
#include "encode/motion.h"
#include "encode/rate_distortion.h"
#include "encode/segmentation/diffusion.h"
#include "encode/segmentation/segmentation.h"
#include "encode/stream_writer.h"
#include "gltf/load.h"
#include "sample_first_animated.h"
#include "sampling/sample.h"
#include "segmorph/decoder_c.h"
#include "stand_in_base.h"

using namespace segmorph;

namespace {

// Everything the stage benchmarks start from.
struct Fixture {
  std::vector<FrameSequence> clips;
  std::vector<float> base;  // the first frame, quantized as Draco's 14-bit default would
  std::vector<uint8_t> stream;
  StreamContent content;
  WeldedTopology topology;
  VertexAdjacency adjacency;
  Trajectories trajectories;
  std::vector<uint32_t> multiplicity;
  std::vector<float> welded;
  ResidualTraversal traversal;
  std::unique_ptr<FramePredictions> predictions;
  size_t vertex_frames = 0;
};
Fixture* fixture = nullptr;

bool set_up(const char* path, double error, bool table_residuals) {
  SampledNode node;
  Status status = bench::sample_first_animated(path, node);
  CodecSettings settings;
  settings.target = error;
  settings.table_residuals = table_residuals;
  Fixture& f = *fixture;
  if (status.ok()) {
    f.clips = node.primitives[0].clips;
    f.base = bench::stand_in_base(f.clips[0]);
    status = encode_animation(f.clips, f.base, settings, f.stream);
  }
  if (status.ok()) status = read_stream(f.stream.data(), f.stream.size(), f.base, f.content);
  if (!status.ok()) {
    std::fprintf(stderr, "codec_benchmark: %s: %s\n", path, status.message().c_str());
    return false;
  }
  f.topology = weld_topology(f.clips);
  f.adjacency = vertex_adjacency(f.topology);
  f.trajectories.vertex_count = f.topology.welded_count();
  for (const FrameSequence& clip : f.clips) {
    f.trajectories.frame_count += clip.frame_count;
    f.vertex_frames += clip.frame_count * clip.vertex_count;
    for (size_t frame = 0; frame < clip.frame_count; ++frame)
      for (uint32_t v : f.topology.representative)
        for (int c = 0; c < 3; ++c) f.trajectories.positions.push_back(clip.frame(frame)[v * 3 + size_t(c)]);
  }
  f.multiplicity.assign(f.topology.welded_count(), 0);
  for (uint32_t w : f.topology.welded_index) ++f.multiplicity[w];
  f.welded = welded_base(f.base, f.content);
  f.traversal = residual_traversal(f.content, f.clips[0].triangles);
  f.predictions = std::make_unique<FramePredictions>(f.content, f.welded);
  std::fprintf(stderr, "codec_benchmark: %s: V=%zu, %zu vertex-frames, stream %zu bytes (version %d, W=%u, K=%u",
               path, f.clips[0].vertex_count, f.vertex_frames, f.stream.size(), int(f.stream[4]),
               f.content.welded_count, f.content.cluster_count);
  if (f.content.transform)
    std::fprintf(stderr, ", %zu coefficients, %.1f per welded vertex, %zu stream basis vectors",
                 f.content.coefficient_symbols.size(),
                 double(f.content.coefficient_symbols.size()) / double(f.content.welded_count),
                 f.content.stream_basis.size());
  std::fprintf(stderr, ")\n");
  return true;
}

void vertex_frame_rate(benchmark::State& state) {
  state.counters["vf/s"] =
      benchmark::Counter(double(fixture->vertex_frames) * double(state.iterations()), benchmark::Counter::kIsRate);
}

// --- Encoder ---

void EncodeWhole(benchmark::State& state) {
  CodecSettings settings;
  std::vector<uint8_t> stream;
  for (auto _ : state) {
    Status status = encode_animation(fixture->clips, fixture->base, settings, stream);
    benchmark::DoNotOptimize(stream.data());
    if (!status.ok()) state.SkipWithError(status.message().c_str());
  }
  vertex_frame_rate(state);
}
BENCHMARK(EncodeWhole)->Unit(benchmark::kMillisecond);

void EncodeSpectralMorseFunction(benchmark::State& state) {
  const Fixture& f = *fixture;
  std::vector<double> positions(f.topology.welded_count() * 3);
  for (size_t w = 0; w < f.topology.welded_count(); ++w)
    for (int c = 0; c < 3; ++c)
      positions[w * 3 + size_t(c)] = f.clips[0].frame(0)[f.topology.representative[w] * 3 + size_t(c)];
  for (auto _ : state) {
    MorseFunction morse;
    Status status = diffusion_morse_function(positions, f.topology, f.adjacency, DiffusionSettings(), morse);
    benchmark::DoNotOptimize(morse.mu.data());
    if (!status.ok()) state.SkipWithError(status.message().c_str());
  }
}
BENCHMARK(EncodeSpectralMorseFunction)->Unit(benchmark::kMillisecond);

void EncodeAffineMotion(benchmark::State& state) {
  const Fixture& f = *fixture;
  Clusters clusters;
  clusters.count = f.content.cluster_count;
  clusters.label = f.content.labels;
  for (auto _ : state)
    benchmark::DoNotOptimize(fit_affine_motion(f.welded.data(), f.trajectories, clusters).transforms.data());
  vertex_frame_rate(state);
}
BENCHMARK(EncodeAffineMotion)->Unit(benchmark::kMillisecond);

void EncodePrediction(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(predicted_frames(fixture->content, fixture->welded).data());
  vertex_frame_rate(state);
}
BENCHMARK(EncodePrediction)->Unit(benchmark::kMillisecond);

// The closed-loop D(q), R(q) of the three subbands at state.range(0) candidate steps each, the predictions computed
// frame by frame inside, as the encoder does (since 1b36209; before, they were computed beforehand, outside the
// timing).
void EncodeMeasureSubbands(benchmark::State& state) {
  const Fixture& f = *fixture;
  std::vector<double> steps[3];
  for (int axis = 0; axis < 3; ++axis) {
    for (int64_t j = 0; j < state.range(0); ++j)  // quarter-octaves from the encoder's choice
      steps[axis].push_back(f.content.residual_step[axis] * std::exp2(double(j) / 4.0));
  }
  for (auto _ : state) {
    SubbandCurve curves[3];
    measure_subbands(f.content, f.traversal, *f.predictions, f.trajectories.positions, f.multiplicity, steps, curves);
    benchmark::DoNotOptimize(curves[0].bits.data());
  }
  state.counters["vf/s"] =
      benchmark::Counter(double(f.vertex_frames) * 3.0 * double(steps[0].size()) * double(state.iterations()),
                         benchmark::Counter::kIsRate);
}
BENCHMARK(EncodeMeasureSubbands)->Arg(1)->Arg(3)->Arg(5)->Unit(benchmark::kMillisecond);

void EncodeEntropy(benchmark::State& state) {
  std::vector<uint8_t> out;
  for (auto _ : state) {
    out.clear();
    write_stream(fixture->content, fixture->base, out);
    benchmark::DoNotOptimize(out.data());
  }
  vertex_frame_rate(state);
}
BENCHMARK(EncodeEntropy)->Unit(benchmark::kMillisecond);

// --- Decoder ---

void DecodeWhole(benchmark::State& state) {
  const Fixture& f = *fixture;
  std::vector<FrameSequence> clips;
  for (auto _ : state) {
    Status status = decode_animation(f.stream.data(), f.stream.size(), f.base, f.clips[0].triangles, clips);
    benchmark::DoNotOptimize(clips.data());
    if (!status.ok()) state.SkipWithError(status.message().c_str());
  }
  vertex_frame_rate(state);
}
BENCHMARK(DecodeWhole)->Unit(benchmark::kMillisecond);

void DecodeEntropy(benchmark::State& state) {
  const Fixture& f = *fixture;
  for (auto _ : state) {
    StreamContent content;
    Status status = read_stream(f.stream.data(), f.stream.size(), f.base, content);
    benchmark::DoNotOptimize(content.residuals.data());
    if (!status.ok()) state.SkipWithError(status.message().c_str());
  }
  vertex_frame_rate(state);
}
BENCHMARK(DecodeEntropy)->Unit(benchmark::kMillisecond);

// The runtime decoder's C API (include/segmorph/decoder_c.h), as a player that keeps every frame uses it: open the
// stream, each clip into memory the caller allocated beforehand.
void DecodeApiClips(benchmark::State& state) {
  const Fixture& f = *fixture;
  segmorph_decoder* decoder = segmorph_decoder_create();
  std::vector<std::vector<float>> clips;
  for (const FrameSequence& clip : f.clips) clips.emplace_back(clip.positions.size());
  for (auto _ : state) {
    segmorph_status status = segmorph_decoder_open(decoder, f.stream.data(), f.stream.size(), f.base.data(),
                                                   f.base.size() / 3, f.clips[0].triangles.data(),
                                                   f.clips[0].triangles.size());
    for (size_t c = 0; status == SEGMORPH_STATUS_OK && c < clips.size(); ++c)
      status = segmorph_decode_clip(decoder, c, clips[c].data(), clips[c].size());
    benchmark::DoNotOptimize(clips.data());
    if (status != SEGMORPH_STATUS_OK) state.SkipWithError(segmorph_decoder_message(decoder));
  }
  segmorph_decoder_destroy(decoder);
  vertex_frame_rate(state);
}
BENCHMARK(DecodeApiClips)->Unit(benchmark::kMillisecond);

// The C API as a streaming player uses it: open the stream, then every frame into one V × 3 buffer.
void DecodeApiFrames(benchmark::State& state) {
  const Fixture& f = *fixture;
  segmorph_decoder* decoder = segmorph_decoder_create();
  std::vector<float> frame(f.base.size());
  size_t frames = 0;
  for (const FrameSequence& clip : f.clips) frames += clip.frame_count;
  for (auto _ : state) {
    segmorph_status status = segmorph_decoder_open(decoder, f.stream.data(), f.stream.size(), f.base.data(),
                                                   f.base.size() / 3, f.clips[0].triangles.data(),
                                                   f.clips[0].triangles.size());
    for (size_t i = 0; status == SEGMORPH_STATUS_OK && i < frames; ++i) {
      status = segmorph_decode_frame(decoder, frame.data(), frame.size());
      benchmark::DoNotOptimize(frame.data());
    }
    if (status != SEGMORPH_STATUS_OK) state.SkipWithError(segmorph_decoder_message(decoder));
  }
  segmorph_decoder_destroy(decoder);
  vertex_frame_rate(state);
}
BENCHMARK(DecodeApiFrames)->Unit(benchmark::kMillisecond);

// The stream up to its residuals: header, welding, labels, motion, weights.
void DecodeHead(benchmark::State& state) {
  const Fixture& f = *fixture;
  for (auto _ : state) {
    StreamContent content;
    StreamReader reader(f.stream.data(), f.stream.size());
    Status status = reader.read_head(f.base, content);
    benchmark::DoNotOptimize(content.weight_value.data());
    if (!status.ok()) state.SkipWithError(status.message().c_str());
  }
  // What the head holds most of in version 4: the coefficients' symbols (and the stream's bytes, all in the head).
  if (f.content.transform) {
    state.counters["coefficients/s"] = benchmark::Counter(
        double(f.content.coefficient_symbols.size()) * double(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["B/s"] =
        benchmark::Counter(double(f.stream.size()) * double(state.iterations()), benchmark::Counter::kIsRate);
  }
}
BENCHMARK(DecodeHead)->Unit(benchmark::kMillisecond);

// Everything after entropy decoding: per frame, the prediction, the residual loop and the original vertex order.
void DecodeFrames(benchmark::State& state) {
  const Fixture& f = *fixture;
  std::vector<FrameSequence> clips;
  for (auto _ : state) {
    Status status = reconstruct_clips(f.content, f.base, f.clips[0].triangles, clips);
    benchmark::DoNotOptimize(clips.data());
    if (!status.ok()) state.SkipWithError(status.message().c_str());
  }
  vertex_frame_rate(state);
}
BENCHMARK(DecodeFrames)->Unit(benchmark::kMillisecond);

// The practical limit of a decoder: copying the restored frames (V × F × 3 floats) once.
void DecodeFrameCopyLimit(benchmark::State& state) {
  const Fixture& f = *fixture;
  std::vector<float> copy;
  for (auto _ : state)
    for (const FrameSequence& clip : f.clips) {
      copy.assign(clip.positions.begin(), clip.positions.end());
      benchmark::DoNotOptimize(copy.data());
    }
  vertex_frame_rate(state);
}
BENCHMARK(DecodeFrameCopyLimit)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::string path = SEGMORPH_SOURCE_DIR "/../shared/samples/sequences/Cow_pcow/cow.glb";
  double error = 0.15;
  bool table_residuals = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--error") == 0 && i + 1 < argc)
      error = std::atof(argv[++i]);
    else if (std::strcmp(argv[i], "--fast-decode") == 0)
      table_residuals = true;
    else if (argv[i][0] != '-')
      path = argv[i];
    else {
      std::fprintf(stderr, "codec_benchmark: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  Fixture storage;
  fixture = &storage;
  if (!set_up(path.c_str(), error, table_residuals)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
