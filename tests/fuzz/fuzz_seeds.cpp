// Writes the seed corpus of fuzz_animation_stream: valid streams of small synthetic animations of the fuzzer's
// base mesh, one per codec configuration (lossy at several targets, lossless, fixed cluster counts, each residual
// predictor on and off, several clips; version 1 with the adaptive residual code, version 2 with the table code,
// version 3 with frame references, on animations that repeat their frames, and with the motion's and the weights'
// contexts, and version 4 with the residuals as bases and coefficients), so that mutations start from every path of
// the decoder. Each stream is checked to be of the version its
// settings ask for and to decode to the encoder's reconstruction before it is written.
//
//   fuzz_seeds OUTPUT_DIRECTORY
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "common/stream.h"
#include "common/stream_format.h"
#include "decode/frame_decoder.h"
#include "decode/stream_reader.h"
#include "encode/encoder.h"
#include "encode/stream_writer.h"
#include "fuzz_base_mesh.h"

namespace segmorph::fuzz {
namespace {

constexpr uint32_t kJumping = 20;

// Frame f of a clip of `frames` frames: the sphere's right half bends about z with a travelling ripple, the seam
// copies 44, 45 and the third copy of vertex 4 tear away from their originals (so that the decoder meets groups
// of identical base positions that are welded and groups that are not), the loose triangle turns, the isolated
// vertex drifts, and sphere vertex kJumping jumps between x = ±6, far from its cluster's motion (in lossless
// streams, differences of float bit patterns beyond int32, which the stream codes with an escape). Frame 0 of
// clip 0 is the base mesh.
std::vector<float> frame_positions(const BaseMesh& mesh, size_t clip, size_t f, size_t frames) {
  const double t = double(f) / double(frames), bend = clip % 2 ? -0.8 : 1.2, phase = double(clip);
  std::vector<float> positions = mesh.positions;
  if (clip == 0 && f == 0) return positions;
  for (uint32_t v = 0; v < kLoose; ++v) {
    const double x = mesh.positions[v * 3], y = mesh.positions[v * 3 + 1];
    const double angle = x > 0 ? bend * t * x / 2 : 0.0;
    const double ripple = 0.05 * std::sin(3 * x + 6.28 * t + phase);
    positions[v * 3] = float(x * std::cos(angle) - y * std::sin(angle));
    positions[v * 3 + 1] = float(x * std::sin(angle) + y * std::cos(angle) + ripple);
  }
  for (uint32_t v : {kSeam + 2, kSeam + 3, kSplit + 1})
    positions[v * 3 + 2] += float(0.1 * t);
  const double turn = 0.5 * t + 0.2 * phase;
  for (uint32_t v = kLoose; v < kLoose + 3; ++v) {
    const double x = mesh.positions[v * 3] - 3.0, y = mesh.positions[v * 3 + 1];
    positions[v * 3] = float(3.0 + x * std::cos(turn) - y * std::sin(turn));
    positions[v * 3 + 1] = float(x * std::sin(turn) + y * std::cos(turn));
  }
  positions[kIsolated * 3 + 1] += float(t);
  positions[kJumping * 3] = f % 2 ? 6.0f : -6.0f;
  return positions;
}

// Clips of the given frame counts; with a period, each clip repeats its first `period` frames (a cycle played again).
std::vector<FrameSequence> animation(const BaseMesh& mesh, const std::vector<size_t>& clip_frames, size_t period) {
  std::vector<FrameSequence> clips;
  for (size_t c = 0; c < clip_frames.size(); ++c) {
    FrameSequence clip;
    clip.vertex_count = mesh.vertex_count();
    clip.frame_count = clip_frames[c];
    clip.triangles = mesh.triangles;
    for (size_t f = 0; f < clip.frame_count; ++f) {
      const std::vector<float> frame = period ? frame_positions(mesh, c, f % period, period)
                                              : frame_positions(mesh, c, f, clip.frame_count);
      clip.positions.insert(clip.positions.end(), frame.begin(), frame.end());
      clip.times.push_back(float(f) / 30);
    }
    clips.push_back(std::move(clip));
  }
  return clips;
}

struct Seed {
  const char* name;
  CodecSettings settings;
  std::vector<size_t> clip_frames;
  size_t period = 0;  // with frame references: the clips repeat their frames with this period
  // The stream written again with version 3's weight contexts, which the encoder finds too costly on a mesh this
  // small: the weights' other coding reaches the fuzzer only so.
  bool force_weight_contexts = false;
};

// Without version 3's tools (frame references, the motion's and the weights' contexts) unless references() or
// contexts(), or a seed forces the weights' contexts, and without version 4's unless transform(): the seeds of
// versions 1 and 2 stay of those versions whatever the encoder finds in their frames.
CodecSettings lossy(double error) {
  CodecSettings settings;
  settings.target = error;
  settings.frame_references = settings.motion_contexts = settings.weight_contexts = false;
  settings.transform_residuals = false;
  return settings;
}

CodecSettings lossless() {
  CodecSettings settings;
  settings.mode = RateMode::lossless;
  settings.frame_references = settings.motion_contexts = settings.weight_contexts = false;
  settings.transform_residuals = false;
  return settings;
}

CodecSettings bpvf(double bits) {
  CodecSettings settings;
  settings.frame_references = settings.motion_contexts = settings.weight_contexts = false;
  settings.transform_residuals = false;
  settings.mode = RateMode::bpvf;
  settings.target = bits;
  return settings;
}

CodecSettings with_clusters(CodecSettings settings, size_t clusters) {
  settings.clusters = clusters;
  return settings;
}

CodecSettings with_residuals(CodecSettings settings, bool temporal, bool spatial) {
  settings.temporal_residuals = temporal;
  settings.spatial_residuals = spatial;
  return settings;
}

// The residuals in the table code (stream version 2).
CodecSettings table(CodecSettings settings) {
  settings.table_residuals = true;
  return settings;
}

// Each frame's reference and the motion's coding chosen by the encoder (stream version 3).
CodecSettings references(CodecSettings settings) {
  settings.frame_references = settings.motion_contexts = true;
  return settings;
}

// The motion's coding chosen by the encoder (stream version 3 where contexts or linear prediction pay).
CodecSettings contexts(CodecSettings settings) {
  settings.motion_contexts = true;
  return settings;
}

// The residuals as bases and coefficients (stream version 4, where that is smaller: the seeds below are).
CodecSettings transform(CodecSettings settings) {
  settings.transform_residuals = true;
  return settings;
}

// The paper's plain scheme: no refinements, no blending.
CodecSettings plain(CodecSettings settings) {
  settings.curvature_refinement = false;
  settings.motion_refinement = false;
  settings.blend_weights = false;
  return settings;
}

std::vector<Seed> seeds() {
  return {
      {"lossy_error_0.5", lossy(0.5), {8}},
      {"lossy_error_0.05", lossy(0.05), {8}},
      {"lossy_bpvf_4", bpvf(4), {10}},
      {"lossy_three_clips", lossy(0.15), {6, 3, 1}},
      {"lossy_clusters_1", with_clusters(lossy(0.15), 1), {6}},
      {"lossy_clusters_2", with_clusters(lossy(0.15), 2), {6, 4}},
      {"lossy_plain_no_prediction", with_residuals(plain(lossy(0.15)), false, false), {6}},
      {"lossy_temporal_only", with_residuals(lossy(0.15), true, false), {6}},
      {"lossy_spatial_only", with_residuals(lossy(0.15), false, true), {6}},
      {"lossless", lossless(), {6, 4}},
      {"lossless_clusters_3_no_prediction", with_residuals(with_clusters(lossless(), 3), false, false), {5}},
      {"lossless_temporal_only", with_residuals(lossless(), true, false), {5}},
      {"lossless_spatial_only", with_residuals(plain(lossless()), false, true), {5}},
      {"table_error_0.5", table(lossy(0.5)), {8}},
      {"table_error_0.05", table(lossy(0.05)), {8}},
      {"table_bpvf_4", table(bpvf(4)), {10}},
      {"table_three_clips", table(lossy(0.15)), {6, 3, 1}},
      {"table_clusters_1_no_prediction", table(with_residuals(with_clusters(lossy(0.15), 1), false, false)), {6}},
      {"table_plain_temporal_only", table(with_residuals(plain(lossy(0.15)), true, false)), {7}},
      {"references_error_0.15", references(lossy(0.15)), {12}, 4},
      {"references_error_0.5_two_clips", references(lossy(0.5)), {9, 8}, 3},
      {"references_bpvf_4", references(bpvf(4)), {10}, 5},
      {"references_lossless", references(lossless()), {8, 6}, 3},
      {"references_table", table(references(lossy(0.15))), {12}, 4},
      {"motion_contexts_error_0.15", contexts(lossy(0.15)), {24}},
      {"motion_contexts_lossless_two_clips", contexts(lossless()), {16, 9}},
      {"weight_contexts_error_0.15", with_clusters(lossy(0.15), 6), {10}, 0, true},
      {"weight_contexts_references_two_clips", references(lossy(0.5)), {9, 8}, 3, true},
      {"transform_error_0.15", transform(lossy(0.15)), {10}},
      {"transform_error_0.5_three_clips", transform(lossy(0.5)), {6, 3, 1}},
      {"transform_clusters_3", transform(with_clusters(lossy(0.05), 3)), {12}},
      {"transform_references", transform(references(lossy(0.15))), {12}, 4},
  };
}

}  // namespace
}  // namespace segmorph::fuzz

int main(int argc, char** argv) {
  using namespace segmorph;
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds OUTPUT_DIRECTORY\n");
    return 2;
  }
  const std::filesystem::path directory = argv[1];
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) {
    std::fprintf(stderr, "fuzz_seeds: %s: cannot create: %s\n", argv[1], error.message().c_str());
    return 1;
  }
  const fuzz::BaseMesh mesh = fuzz::base_mesh();
  for (const fuzz::Seed& seed : fuzz::seeds()) {
    const std::vector<FrameSequence> clips = fuzz::animation(mesh, seed.clip_frames, seed.period);
    std::vector<uint8_t> stream;
    std::vector<FrameSequence> reconstruction, decoded;
    Status status = encode_animation(clips, mesh.positions, seed.settings, stream, nullptr, &reconstruction);
    if (status.ok() && seed.force_weight_contexts) {
      StreamContent content;
      status = read_stream(stream.data(), stream.size(), mesh.positions, content);
      if (status.ok() && content.weight_cluster.empty()) status = Status(StatusCode::internal, "no extra weights");
      if (status.ok()) {
        content.flags |= format::kFlagWeightContexts;
        stream.clear();
        write_stream(content, mesh.positions, stream);
      }
    }
    const bool version_3 = seed.settings.frame_references || seed.settings.motion_contexts ||
                           seed.settings.weight_contexts || seed.force_weight_contexts;
    const int version = seed.settings.transform_residuals ? 4 : version_3 ? 3 : seed.settings.table_residuals ? 2 : 1;
    if (status.ok() && (stream.size() < 5 || stream[4] != version))
      status = Status(StatusCode::internal, "not a version-" + std::to_string(version) + " stream");
    if (status.ok()) status = decode_animation(stream.data(), stream.size(), mesh.positions, mesh.triangles, decoded);
    if (status.ok())
      for (size_t c = 0; c < clips.size(); ++c)
        if (decoded[c].positions != reconstruction[c].positions)
          status = Status(StatusCode::bad_data, "decodes to other frames than the encoder's reconstruction");
    if (!status.ok()) {
      std::fprintf(stderr, "fuzz_seeds: %s: %s\n", seed.name, status.message().c_str());
      return 1;
    }
    const std::filesystem::path path = directory / (std::string(seed.name) + ".sgma");
    std::ofstream file(path, std::ios::binary);
    file.write(reinterpret_cast<const char*>(stream.data()), std::streamsize(stream.size()));
    if (!file.flush()) {
      std::fprintf(stderr, "fuzz_seeds: %s: cannot write\n", path.c_str());
      return 1;
    }
  }
  return 0;
}
