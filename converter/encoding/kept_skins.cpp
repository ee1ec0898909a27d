#include "encoding/kept_skins.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "decoding/decode_file.h"
#include "encode/rate_target.h"
#include "encoding/track_precision.h"
#include "sampling/sample.h"
#include "track_streams.h"
#include "verify/comparison.h"

namespace segmorph {
namespace {

// The tracks' quantization distance where nothing measured depends on it: this fraction of the error target times
// the scene's diagonal, about what the search settles on for kept skins.
constexpr double kTrackDistanceRatio = 0.25;
// The search: a bracket in at most kBracketRounds doublings or halvings, then kHalvings bisections of it.
constexpr int kBracketRounds = 8, kHalvings = 4;

// The search measures on at most kSearchFrames frames per clip (every k-th): a proxy for every frame at a fraction of
// the cost of sampling and comparing them all. The distance it settles on is then measured on every frame.
constexpr size_t kSearchFrames = 24;

// The most bytes of buffers the search holds decoded whole beside each measurement's copy.
constexpr size_t kHeldDecodeBytes = size_t(256) << 20;

// `sampled` with every k-th frame of each clip, k such that a clip keeps at most kSearchFrames.
std::vector<SampledNode> thinned(const std::vector<SampledNode>& sampled) {
  std::vector<SampledNode> out;
  for (const SampledNode& node : sampled) {
    SampledNode thin;
    thin.node = node.node;
    thin.clip_is_step = node.clip_is_step;
    for (const SampledPrimitive& primitive : node.primitives) {
      SampledPrimitive kept;
      kept.primitive = primitive.primitive;
      for (const FrameSequence& clip : primitive.clips) {
        const size_t step = (clip.frame_count + kSearchFrames - 1) / kSearchFrames;
        FrameSequence frames;
        frames.vertex_count = clip.vertex_count;
        frames.triangles = clip.triangles;
        for (size_t f = 0; f < clip.frame_count; f += std::max<size_t>(step, 1)) {
          frames.times.push_back(clip.times[f]);
          frames.positions.insert(frames.positions.end(), clip.frame(f), clip.frame(f) + clip.vertex_count * 3);
          ++frames.frame_count;
        }
        kept.clips.push_back(std::move(frames));
      }
      thin.primitives.push_back(std::move(kept));
    }
    out.push_back(std::move(thin));
  }
  return out;
}

// The worst KG error (%) of `encoded` against `reference`, frames of the file it was encoded from, as verify
// measures it.
Status measured_kg(const SampledFile& file, const std::vector<SampledNode>& reference, tinygltf::Model&& encoded,
                   VertexMatches& matches, size_t threads, double& kg) {
  SEGMORPH_RETURN_IF_ERROR(decode_compressed_positions(encoded));
  Scene scene;
  SEGMORPH_RETURN_IF_ERROR(analyze_scene(encoded, scene));
  AnimationComparison comparison;
  SEGMORPH_RETURN_IF_ERROR(
      compare_animation(file.model, file.scene, reference, encoded, scene, comparison, true, &matches, threads));
  kg = comparison.worst.kg_percent;
  return Status::Ok();
}

}  // namespace

Status code_tracks(const SampledFile& file, const CodecSettings& codec, bool kept_skins, tinygltf::Model& model,
                   TrackCoding& coding, const Progress& progress, double settled) {
  coding = TrackCoding();
  const double diagonal = scene_diagonal(model);
  const double first = kTrackDistanceRatio * error_target(codec) / 100 * diagonal;
  auto encode = [&](double distance, tinygltf::Model& result) {  // in place
    TrackReport report;
    SEGMORPH_RETURN_IF_ERROR(compress_tracks(result, TrackPrecision{distance, diagonal}, report));
    coding.bytes = report.bytes;
    return Status::Ok();
  };
  if (!kept_skins || codec.mode != RateMode::error) return encode(first, model);

  const double goal = kErrorTargetMargin * codec.target;
  const std::vector<SampledNode> subsample = thinned(file.sampled);
  bool whole = true;  // the subsample is every frame (no clip longer than kSearchFrames)
  for (size_t n = 0; n < subsample.size(); ++n)
    for (size_t c = 0; c < subsample[n].primitives[0].clips.size(); ++c)
      whole = whole && subsample[n].primitives[0].clips[c].frame_count ==
                           file.sampled[n].primitives[0].clips[c].frame_count;
  // The encodes differ in their tracks only: the rest is decoded once (the Draco meshes; the animation streams too
  // where their baked frames stay within kHeldDecodeBytes, since each measurement copies it), each candidate's
  // tracks are coded on a copy of that, and their vertices pair as the first's.
  tinygltf::Model decoded = model, candidate;
  SEGMORPH_RETURN_IF_ERROR(decode_draco_primitives(decoded, codec.threads));
  {
    tinygltf::Model streams = decoded;
    SEGMORPH_RETURN_IF_ERROR(decode_compressed_positions(streams));
    size_t bytes = 0;
    for (const tinygltf::Buffer& buffer : streams.buffers) bytes += buffer.data.size();
    if (bytes <= kHeldDecodeBytes) decoded = std::move(streams);
  }
  double kg = 0, within = 0, beyond = 0;  // distances known within and beyond the goal (0: none yet)
  int measurements = 0;
  VertexMatches matches;
  auto within_goal = [&](double distance, bool every_frame, bool& ok) {
    candidate = decoded;
    SEGMORPH_RETURN_IF_ERROR(encode(distance, candidate));
    SEGMORPH_RETURN_IF_ERROR(
        measured_kg(file, every_frame ? file.sampled : subsample, std::move(candidate), matches, codec.threads, kg));
    ok = kg <= goal;
    char line[160];
    std::snprintf(line, sizeof(line), "kept skins: tracks within %.4g: KG %.4f %% (%s, measurement %d)", distance,
                  kg, every_frame ? "every frame" : "a subsample of frames", ++measurements);
    report_progress(progress, line);
    return Status::Ok();
  };
  bool ok = false;
  // Settled on by a search for the same skins: that distance, when it stays within the goal here.
  auto settle = [&](double at) {
    coding.searched_distance = at;
    return encode(at, model);
  };
  if (settled > 0) {
    SEGMORPH_RETURN_IF_ERROR(within_goal(settled, true, ok));
    if (ok) return settle(settled);
    matches.clear();  // paired on every frame: the search pairs as it would have without the check
  }
  double distance = first;
  for (int round = 0; round < kBracketRounds; ++round) {
    SEGMORPH_RETURN_IF_ERROR(within_goal(distance, false, ok));
    (ok ? within : beyond) = distance;
    if (within > 0 && beyond > 0) break;
    distance = ok ? distance * 2 : distance / 2;
  }
  for (int round = 0; within > 0 && beyond > 0 && round < kHalvings; ++round) {
    distance = std::sqrt(within * beyond);
    SEGMORPH_RETURN_IF_ERROR(within_goal(distance, false, ok));
    (ok ? within : beyond) = distance;
  }
  if (within == 0) {  // even the finest distance tried is above the goal: its error on every frame is the floor
    SEGMORPH_RETURN_IF_ERROR(within_goal(distance * 2, true, ok));
    if (ok) return settle(distance * 2);
  }
  if (within > 0 && whole) return settle(within);  // measured on every frame already
  // The subsample's choice, measured on every frame: finer while a frame left out is above the goal.
  for (int round = 0; within > 0 && round < kBracketRounds; ++round, within /= 2) {
    SEGMORPH_RETURN_IF_ERROR(within_goal(within, true, ok));
    if (ok) return settle(within);
  }
  // No distance brings the error within the goal: it is not the tracks' (a kept skin's weights are bytes).
  coding = TrackCoding();
  coding.kept_skins_floor = kg;
  return Status::Ok();
}

}  // namespace segmorph
