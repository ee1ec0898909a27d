// Measures the codec on one animated glTF file, before the container exists: every clip of its first animated
// primitive is encoded against a stand-in base mesh (the first frame quantized to 14 bits over its bounding
// box, as Draco's default position quantization would), decoded, and checked.
//   codec_sequence FILE [--error E | --bpvf R | --lossless] [--clusters K] [--no-temporal] [--no-blend]
//                       [--no-spatial] [--no-frame-references] [--no-curvature-refinement]
//                       [--level-curve-refinement] [--choose-segmentation] [--no-motion-refinement]
//                       [--fast-decode] [--no-transform]
// Prints one line: clusters, E(Π) before and after refinement, stream bytes (motion / residuals), bits per
// vertex per frame of the stream alone, KG error and RMSE of the decoded frames, encoder and decoder
// milliseconds, and whether the decoder reproduced the encoder's reconstruction exactly.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "decode/frame_decoder.h"
#include "encode/encoder.h"
#include "encode/metrics.h"
#include "gltf/load.h"
#include "sample_first_animated.h"
#include "sampling/sample.h"
#include "stand_in_base.h"

using namespace segmorph;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: codec_sequence FILE [--error E | --bpvf R | --lossless] [--clusters K] [...]\n");
    return 2;
  }
  CodecSettings settings;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--error" && has_value)
      settings.mode = RateMode::error, settings.target = std::atof(argv[++i]);
    else if (arg == "--bpvf" && has_value)
      settings.mode = RateMode::bpvf, settings.target = std::atof(argv[++i]);
    else if (arg == "--lossless")
      settings.mode = RateMode::lossless;
    else if (arg == "--clusters" && has_value)
      settings.clusters = size_t(std::atoi(argv[++i]));
    else if (arg == "--no-temporal")
      settings.temporal_residuals = false;
    else if (arg == "--no-spatial")
      settings.spatial_residuals = false;
    else if (arg == "--no-frame-references")
      settings.frame_references = false;
    else if (arg == "--no-blend")
      settings.blend_weights = false;
    else if (arg == "--no-curvature-refinement")
      settings.curvature_refinement = false;
    else if (arg == "--level-curve-refinement")
      settings.refinement_level_curves = true;
    else if (arg == "--choose-segmentation")
      settings.choose_segmentation = true;
    else if (arg == "--no-motion-refinement")
      settings.motion_refinement = false;
    else if (arg == "--fast-decode")
      settings.table_residuals = true;
    else if (arg == "--no-transform")
      settings.transform_residuals = false;
    else {
      std::fprintf(stderr, "codec_sequence: unknown option %s\n", arg.c_str());
      return 2;
    }
  }
  SampledNode node;
  Status status = bench::sample_first_animated(argv[1], node);
  if (!status.ok()) {
    std::fprintf(stderr, "codec_sequence: %s: %s\n", argv[1], status.message().c_str());
    return 1;
  }
  const std::vector<FrameSequence>& clips = node.primitives[0].clips;
  const size_t vertex_count = clips[0].vertex_count;
  size_t frame_count = 0;
  for (const FrameSequence& clip : clips) frame_count += clip.frame_count;

  const std::vector<float> base = bench::stand_in_base(clips[0]);

  std::vector<uint8_t> stream;
  StreamReport report;
  std::vector<FrameSequence> reconstruction, decoded;
  auto start = std::chrono::steady_clock::now();
  status = encode_animation(clips, base, settings, stream, &report, &reconstruction);
  const double encode_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!status.ok()) {
    std::fprintf(stderr, "codec_sequence: encode: %s\n", status.message().c_str());
    return 1;
  }
  start = std::chrono::steady_clock::now();
  status = decode_animation(stream.data(), stream.size(), base, clips[0].triangles, decoded);
  const double decode_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!status.ok()) {
    std::fprintf(stderr, "codec_sequence: decode: %s\n", status.message().c_str());
    return 1;
  }
  bool closed_loop = true, exact = true;
  ErrorAccumulator accumulator;
  for (size_t c = 0; c < clips.size(); ++c) {
    closed_loop = closed_loop && decoded[c].positions == reconstruction[c].positions;
    exact = exact &&
            std::memcmp(decoded[c].positions.data(), clips[c].positions.data(), clips[c].positions.size() * 4) == 0;
    accumulator.add(clips[c], decoded[c]);
  }
  const ErrorMetrics metrics = accumulator.result();
  std::printf(
      "%s: V=%zu F=%zu K=%zu E(Pi) %.6f -> %.6f | stream %zu B (motion %zu, residuals %zu) %.3f bpvf | "
      "KG %.4f %% RMSE/diag %.2e | encode %.0f ms (segmentation %.0f, motion %.0f, prediction %.0f, rate "
      "control %.0f, entropy %.0f) decode %.1f ms | decode == encoder: %s%s\n",
      argv[1], vertex_count, frame_count, report.clusters, report.e_pi_morse, report.e_pi, stream.size(),
      report.bytes_motion, report.bytes_residuals, bits_per_vertex_frame(stream.size(), vertex_count, frame_count),
      metrics.kg_percent, metrics.rmse_over_diagonal, encode_ms, report.ms_segmentation, report.ms_motion,
      report.ms_prediction, report.ms_rate_control, report.ms_entropy, decode_ms, closed_loop ? "yes" : "NO",
      settings.mode == RateMode::lossless ? (exact ? " | lossless: bit-exact" : " | lossless: NOT EXACT") : "");
  return closed_loop ? 0 : 1;
}
