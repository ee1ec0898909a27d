// The whole-file encode (segmorph::encode, include/segmorph/segmorph.h): which meshes keep their morph targets or their
// skins and which are baked into frames, the second pass of a bpvf target, and with targets automatic the choice
// between kept and baked targets. The kept skins' track search is kept_skins.cpp's; the margins, rate_target.h's.
#include "encoding/encode_file.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include "bake/bake.h"
#include "common/parallel.h"
#include "encode/metrics.h"
#include "encode/rate_target.h"
#include "encoding/compress_primitives.h"
#include "encoding/kept_skins.h"
#include "encoding/moving_meshes.h"
#include "encoding/track_precision.h"
#include "gltf/delivered_size.h"
#include "gltf/packing.h"
#include "gltf/save.h"
#include "segmorph_extension.h"
#include "track_streams.h"
#include "verify/comparison.h"

namespace segmorph {
namespace {

// Whether encode keeps the morph targets of `node` (see --targets): an unskinned morph mesh that only this node
// uses, in a lossy encode, with at most half as many targets as frames unless asked to keep them.
bool keeps_targets(const tinygltf::Model& model, const AnimatedNode& node, const SampledNode& sampled,
                   const EncodeSettings& settings) {
  if (settings.targets == EncodeSettings::Targets::bake || settings.mode == RateMode::lossless) return false;
  if (!node.morphed || node.skin >= 0) return false;
  size_t users = 0;
  for (const tinygltf::Node& other : model.nodes) users += other.mesh == node.mesh;
  if (users != 1) return false;
  if (settings.targets == EncodeSettings::Targets::keep) return true;
  size_t frames = 0;
  for (const FrameSequence& clip : sampled.primitives[0].clips) frames += clip.frame_count;
  return 2 * sampled.primitives[0].target_deltas.size() <= frames;
}

struct Encoded {
  tinygltf::Model model;
  CompressReport report;
  double kept_skins_floor = 0;  // when kept skins cannot reach the --error target: the KG % they stay at
  double track_distance = 0;    // the distance the search for kept skins settled on (0 without one)
  std::vector<PrimitiveMode> modes;  // per sampled node: frames, kept targets or kept skin
  std::vector<int> rigid_meshes;     // meshes of the encode compressed as rigid meshes
  double ms_tracks = 0;
};

// What encode_model_once does with the settings: the codec's and Draco's, whether kept skins stay kept.
struct EncodeChoices {
  CodecSettings codec;
  DracoSettings draco;
  bool keep_skins = true;
  double settled_track_distance = 0;  // code_tracks' `settled`
};

// Bits per vertex per frame are counted over Σ V × F of the sampled primitives and clips.
double vertex_frames(const std::vector<SampledNode>& sampled) {
  double total = 0;
  for (const SampledNode& node : sampled)
    for (const SampledPrimitive& primitive : node.primitives)
      for (const FrameSequence& clip : primitive.clips) total += double(clip.vertex_count) * double(clip.frame_count);
  return total;
}

// Whether encode keeps the skin of `node` (see --skins): a skinned mesh without morph targets, with an error
// target (a kept skin's error is searched for; --bpvf rate control and --lossless are the codec's, on baked frames).
bool keeps_skin(const AnimatedNode& node, const EncodeChoices& choices) {
  return choices.keep_skins && choices.codec.mode == RateMode::error && node.skin >= 0 && !node.morphed;
}

// Encodes a copy of file's model with `codec`: the nodes `keep` marks keep their morph targets, skinned nodes whose
// skin is kept are compressed with the meshes that move rigidly, the others are baked; then the tracks are coded.
Status encode_model_once(const SampledFile& file, const std::vector<bool>& keep, const CodecSettings& codec,
                         const EncodeChoices& choices, const Progress& progress, Encoded& out) {
  out.model = file.model;
  name_generator(out.model);  // before any size is measured
  out.report = CompressReport();
  out.kept_skins_floor = 0;
  out.track_distance = 0;
  out.modes.assign(file.sampled.size(), PrimitiveMode::frames);
  out.rigid_meshes.clear();
  std::vector<const SampledNode*> kept, baked;
  std::vector<int> kept_skins;
  for (size_t i = 0; i < file.sampled.size(); ++i) {
    if (keeps_skin(*file.sampled[i].node, choices)) {
      kept_skins.push_back(file.sampled[i].node->node);
      out.modes[i] = PrimitiveMode::kept_skin;
    } else {
      (keep[i] ? kept : baked).push_back(&file.sampled[i]);
      if (keep[i]) out.modes[i] = PrimitiveMode::kept_targets;
    }
  }
  const auto say = [&](const std::string& message) { report_progress(progress, message); };
  SEGMORPH_RETURN_IF_ERROR(compress_targets(out.model, kept, codec, choices.draco, out.report, say));
  SEGMORPH_RETURN_IF_ERROR(bake_model(out.model, file.scene, baked, false));
  SEGMORPH_RETURN_IF_ERROR(compress_model(out.model, baked, codec, choices.draco, out.report, say));
  if (codec.mode == RateMode::lossless) return Status::Ok();
  // Draco's RMS error is half its step: a step of 2 × share × E / 100 of a mesh's spread is its share of KG E %.
  const double step_ratio = 2 * kMovingMeshErrorShare * error_target(codec) / 100;
  MovingMeshReport meshes;
  // A rigid part's error counts against the whole it belongs to: a figure's spread is about a quarter of its
  // diagonal.
  const double rigid_spread = scene_diagonal(out.model) / 4;
  const std::vector<bool> moving = moving_meshes(out.model, kept_skins);
  for (size_t m = 0; m < moving.size(); ++m) {
    const bool skin = std::any_of(kept_skins.begin(), kept_skins.end(),
                                  [&](int node) { return out.model.nodes[size_t(node)].mesh == int(m); });
    if (moving[m] && !skin) out.rigid_meshes.push_back(int(m));
  }
  SEGMORPH_RETURN_IF_ERROR(
      compress_moving_meshes(out.model, moving, choices.draco, step_ratio, rigid_spread, codec.threads, meshes));
  out.report.draco_bytes += meshes.bytes;
  say(kept_skins.empty() ? "coding the animation tracks" : "coding the animation tracks, measuring the kept skins' error");
  TrackCoding tracks;
  const auto begin = std::chrono::steady_clock::now();
  SEGMORPH_RETURN_IF_ERROR(
      code_tracks(file, codec, !kept_skins.empty(), out.model, tracks, progress, choices.settled_track_distance));
  out.ms_tracks = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  out.report.animation_bytes += tracks.bytes;
  out.kept_skins_floor = tracks.kept_skins_floor;
  out.track_distance = tracks.searched_distance;
  return Status::Ok();
}

// encode_model_once, and with --bpvf a second time: the rate is of the whole file, and the codec budgets only its
// streams and base meshes, so the rest (JSON, images, other meshes and animations, kept weights), measured on the
// first encode, comes off the codec's target.
Status encode_model(const SampledFile& file, const std::vector<bool>& keep, const EncodeChoices& choices,
                    const Progress& progress, Encoded& out) {
  const CodecSettings& codec = choices.codec;  // the file's target
  SEGMORPH_RETURN_IF_ERROR(encode_model_once(file, keep, codec, choices, progress, out));
  if (out.kept_skins_floor > 0) {
    char line[200];
    std::snprintf(line, sizeof(line),
                  "kept skins stay at KG %.4f %% even with the finest tracks, above --error %g (their weights are "
                  "bytes): baking them instead",
                  out.kept_skins_floor, codec.target);
    report_progress(progress, line);
    EncodeChoices baked = choices;
    baked.keep_skins = false;
    const double floor = out.kept_skins_floor;
    SEGMORPH_RETURN_IF_ERROR(encode_model_once(file, keep, codec, baked, progress, out));
    out.kept_skins_floor = floor;
  }
  if (codec.mode != RateMode::bpvf) return Status::Ok();
  const double frames = vertex_frames(file.sampled);
  const size_t coded = out.report.draco_bytes + out.report.animation_bytes, whole = glb_size(out.model);
  const double rest = bits_per_vertex_frame(whole > coded ? whole - coded : 0, frames);
  char figures[200];
  std::snprintf(figures, sizeof(figures), "%.3f bpvf, of which %.3f outside the animation streams and base meshes",
                bits_per_vertex_frame(whole, frames), rest);
  if (rest >= codec.target) {
    char rate[32];
    std::snprintf(rate, sizeof(rate), "%g", codec.target);
    return Status(StatusCode::invalid_argument, std::string("--bpvf ") + rate +
                                                    " is below what the rest of the file takes alone: the first "
                                                    "encode came to " +
                                                    figures);
  }
  report_progress(progress, std::string("first encode: ") + figures + "; encoding again for the whole file's rate");
  CodecSettings streams = codec;  // the streams' and base meshes' share of it
  streams.target -= rest;
  SEGMORPH_RETURN_IF_ERROR(encode_model_once(file, keep, streams, choices, progress, out));
  const double reached = bits_per_vertex_frame(glb_size(out.model), frames);
  if (reached > kBpvfTolerance * codec.target) {
    char line[200];
    std::snprintf(line, sizeof(line), "warning: --bpvf %g is out of reach for this file: it comes to %.3f bpvf",
                  codec.target, reached);
    report_progress(progress, line);
  }
  return Status::Ok();
}

// What the morph targets of the nodes every encode bakes (keep false) held is in their sampled frames: their data
// goes from the sampling and from the model each encode copies, so that a long sequence of one-hot targets is held
// once, as frames. A mesh is released when every node that uses it is baked (a still instance keeps its targets).
void release_baked_targets(SampledFile& file, const std::vector<bool>& keep) {
  std::vector<bool> baked_node(file.model.nodes.size(), false), release(file.model.meshes.size(), false);
  for (size_t i = 0; i < file.sampled.size(); ++i) {
    if (keep[i]) continue;
    baked_node[size_t(file.sampled[i].node->node)] = true;
    release[size_t(file.sampled[i].node->mesh)] = true;
    for (SampledPrimitive& primitive : file.sampled[i].primitives)
      for (std::vector<float>& delta : primitive.target_deltas) std::vector<float>().swap(delta);  // the count stays
  }
  for (size_t n = 0; n < file.model.nodes.size(); ++n) {
    const int mesh = file.model.nodes[n].mesh;
    if (mesh >= 0 && size_t(mesh) < release.size() && !baked_node[n]) release[size_t(mesh)] = false;
  }
  release_target_data(file.model, release);
}

// The worst KG error (%) the encoder reports over the encoded primitives.
double worst_kg(const CompressReport& report) {
  double worst = 0;
  for (const StreamReport& primitive : report.primitives) worst = std::max(worst, primitive.kg_percent);
  return worst;
}

// The bytes of a primitive of an encoded model: its Draco mesh's and its animation stream's buffer views.
size_t coded_bytes(const tinygltf::Model& model, int mesh, int primitive) {
  size_t bytes = 0;
  const tinygltf::Primitive& coded = model.meshes[size_t(mesh)].primitives[size_t(primitive)];
  for (const char* name : {kDracoExtensionName, kExtensionName}) {
    const auto extension = coded.extensions.find(name);
    if (extension == coded.extensions.end() || !extension->second.Has("bufferView")) continue;
    const int view = extension->second.Get("bufferView").GetNumberAsInt();
    if (view >= 0 && size_t(view) < model.bufferViews.size()) bytes += model.bufferViews[size_t(view)].byteLength;
  }
  return bytes;
}

// The report's primitives and errors, measured as verify measures them: the encode decoded and compared with the
// input's sampled frames.
Status measure(const SampledFile& file, const Encoded& encoded, size_t threads, EncodeReport& report,
               const Progress& progress) {
  const auto begin = std::chrono::steady_clock::now();
  SampledFile decoded;
  AnimationComparison comparison;
  report_progress(progress, "measuring the encode against the input: decoding it");
  tinygltf::Model model = encoded.model;
  // On every thread (analyze_model's own decode would use one; it finds nothing compressed left).
  Status status = decode_compressed_positions(model, threads);
  if (status.ok()) status = analyze_model(std::move(model), SampleSettings(), false, {}, decoded);
  report_progress(progress, "measuring the encode against the input: comparing the frames");
  if (status.ok())
    status = compare_animation(file.model, file.scene, file.sampled, decoded.model, decoded.scene, comparison, true,
                               nullptr, threads);
  if (!status.ok()) return Status(StatusCode::internal, "measuring the encode against the input: " + status.message());
  for (const PrimitiveComparison& compared : comparison.primitives) {
    EncodedPrimitive primitive;
    for (size_t i = 0; i < file.sampled.size(); ++i)
      if (file.sampled[i].node->node == compared.node) primitive.mode = encoded.modes[i];
    // Decoding may renumber meshes, never nodes: the encoded primitive is that of the node the comparison paired.
    primitive.output_mesh = encoded.model.nodes[size_t(compared.other_node)].mesh;
    primitive.output_primitive = compared.other_primitive;
    for (const StreamReport& stream : encoded.report.primitives)
      if (stream.mesh == primitive.output_mesh && stream.primitive == primitive.output_primitive)
        primitive.clusters = stream.clusters;
    primitive.bytes = coded_bytes(encoded.model, primitive.output_mesh, primitive.output_primitive);
    const StreamKind stream = compressed_stream_kind(encoded.model, primitive.output_mesh, primitive.output_primitive);
    primitive.stream_version = stream.version;
    primitive.gpu_playable = stream.gpu_playable();
    primitive.error = primitive_error(file.model, compared);
    report.primitives.push_back(primitive);
  }
  // The rigid meshes' primitives, each measured on the first node that uses its mesh (moving_meshes takes only meshes
  // that nodes use) and named by its output mesh and primitive: compared on the threads, reported in order.
  std::vector<PrimitiveComparison> rigid;
  for (int mesh : encoded.rigid_meshes)
    for (size_t p = 0; p < encoded.model.meshes[size_t(mesh)].primitives.size(); ++p) {
      PrimitiveComparison compared;
      compared.mesh = mesh, compared.primitive = int(p);
      for (size_t n = 0; n < encoded.model.nodes.size() && compared.node < 0; ++n)
        if (encoded.model.nodes[n].mesh == mesh) compared.node = int(n);
      rigid.push_back(compared);
    }
  std::vector<Status> rigid_status(rigid.size());
  parallel_items(rigid.size(), thread_count(threads), [&](size_t i) {
    rigid_status[i] = compare_rigid_primitive(file.model, file.scene, decoded.model, decoded.scene, rigid[i].node,
                                              rigid[i].primitive, rigid[i].metrics);
  });
  for (size_t i = 0; i < rigid.size(); ++i) {
    if (!rigid_status[i].ok())
      return Status(StatusCode::internal, "measuring the encode's rigid mesh " + std::to_string(rigid[i].mesh) +
                                              " against the input: " + rigid_status[i].message());
    EncodedPrimitive primitive;
    primitive.mode = PrimitiveMode::rigid;
    primitive.output_mesh = rigid[i].mesh;
    primitive.output_primitive = rigid[i].primitive;
    primitive.bytes = coded_bytes(encoded.model, rigid[i].mesh, rigid[i].primitive);
    primitive.error = primitive_error(encoded.model, rigid[i]);
    report.primitives.push_back(primitive);
  }
  report.kg_percent = comparison.worst.kg_percent;
  report.rmse_over_diagonal = comparison.worst.rmse_over_diagonal;
  report.max_error_over_diagonal = comparison.worst.max_error_over_diagonal;
  report.ms_measure = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  return Status::Ok();
}

}  // namespace

Status encode_sampled(SampledFile& file, const EncodeSettings& settings, tinygltf::Model& output,
                      EncodeReport& report, const Progress& progress) {
  if (settings.max_stream_version < 1 || settings.max_stream_version > 4)
    return Status(StatusCode::invalid_argument, "the stream version must be 1 to 4");
  if (settings.fast_decode && settings.max_stream_version < 2)
    return Status(StatusCode::invalid_argument, "fast decoding writes stream version 2");
  if (settings.gpu_playable &&
      (settings.mode != RateMode::error || settings.fast_decode || settings.max_stream_version < 4))
    return Status(StatusCode::invalid_argument,
                  "GPU-playable streams (version 4) need an error target, no fast decoding and stream version 4");
  EncodeChoices choices;
  choices.codec.mode = settings.mode;
  choices.codec.gpu_playable = settings.gpu_playable;
  choices.codec.target = settings.target;
  choices.codec.clusters = settings.clusters;
  choices.codec.table_residuals = settings.fast_decode;
  choices.codec.frame_references = choices.codec.motion_contexts = choices.codec.weight_contexts =
      settings.max_stream_version >= 3;
  choices.codec.transform_residuals = settings.max_stream_version >= 4;
  choices.codec.threads = settings.threads;
  choices.draco.position_bits = settings.position_bits;
  choices.draco.normal_bits = settings.normal_bits;
  choices.draco.texcoord_bits = settings.texcoord_bits;
  choices.keep_skins = settings.skins == EncodeSettings::Skins::keep;
  // Morph-target meshes that keep their targets are compressed where they are; the others are baked first. With
  // --targets auto, a file where some mesh could keep them is encoded both ways; the file smaller as delivered
  // (glb_delivered_estimate) is kept (with --bpvf, where both come to the target's size, the one with the smaller
  // worst error).
  std::vector<bool> keep(file.sampled.size());
  bool any_kept = false;
  for (size_t i = 0; i < file.sampled.size(); ++i)
    any_kept |= keep[i] = keeps_targets(file.model, *file.sampled[i].node, file.sampled[i], settings);
  release_baked_targets(file, keep);
  Encoded encoded;
  Status status = encode_model(file, keep, choices, progress, encoded);
  if (any_kept && settings.targets == EncodeSettings::Targets::automatic) {
    // Either variant may be refused (a --bpvf target below what its rest takes); the other then stands alone.
    Encoded baked;
    report_progress(progress, "encoding again with the morph targets baked, to compare");
    // Its kept skins are the first's: their tracks start from the distance the first's search settled on.
    EncodeChoices again = choices;
    if (status.ok()) again.settled_track_distance = encoded.track_distance;
    const Status baked_status = encode_model(file, std::vector<bool>(keep.size(), false), again, progress, baked);
    if (!status.ok() && baked_status.ok()) {
      report_progress(progress, "keeping the morph targets was refused (" + status.message() + "); the baked file stands");
      encoded = std::move(baked), status = baked_status;
    } else if (status.ok() && baked_status.ok()) {
      size_t kept_size = 0, baked_size = 0;
      const size_t kept_delivered = glb_delivered_estimate(encoded.model, &kept_size),
                   baked_delivered = glb_delivered_estimate(baked.model, &baked_size);
      const double kept_kg = worst_kg(encoded.report), baked_kg = worst_kg(baked.report);
      char line[200];
      std::snprintf(line, sizeof(line),
                    "morph targets kept: %zu bytes (about %zu compressed), KG %.4f %%; baked: %zu bytes (about %zu "
                    "compressed), KG %.4f %%",
                    kept_size, kept_delivered, kept_kg, baked_size, baked_delivered, baked_kg);
      report_progress(progress, line);
      // The file smaller as a server sends it (the kept targets' weights animation is float data a compressor
      // shrinks, the streams are not); with --bpvf, whose budget counts the file's bytes: the smaller error among
      // the files within the target, else the smaller file.
      const double budget = kBpvfTolerance * settings.target * vertex_frames(file.sampled) / 8;
      const bool kept_fits = double(kept_size) <= budget, baked_fits = double(baked_size) <= budget;
      const bool take_baked = settings.mode != RateMode::bpvf ? baked_delivered < kept_delivered
                              : kept_fits != baked_fits       ? baked_fits
                              : kept_fits                     ? baked_kg < kept_kg
                                                              : baked_size < kept_size;
      if (take_baked) encoded = std::move(baked);
    }
  }
  SEGMORPH_RETURN_IF_ERROR(status);
  // K is merged down from the Morse segmentation's clusters, never split up: a larger --clusters is said, not hidden.
  for (const StreamReport& stream : encoded.report.primitives)
    if (settings.clusters > stream.clusters) {
      report_progress(progress, "warning: --clusters " + std::to_string(settings.clusters) + " is more than the " +
                                    "segmentation gives a primitive (" + std::to_string(stream.clusters) +
                                    " clusters): it is coded with " + std::to_string(stream.clusters));
      break;
    }
  report = EncodeReport();
  SEGMORPH_RETURN_IF_ERROR(measure(file, encoded, settings.threads, report, progress));
  report.glb_bytes = glb_size(encoded.model);
  report.ms_tracks = encoded.ms_tracks;
  output = std::move(encoded.model);
  report.streams = std::move(encoded.report.primitives);
  report.draco_bytes = encoded.report.draco_bytes;
  report.animation_bytes = encoded.report.animation_bytes;
  report.ms_draco = encoded.report.ms_draco;
  report.kept_skins_floor = encoded.kept_skins_floor;
  report.vertex_frames = vertex_frames(file.sampled);
  for (const StreamReport& stream : report.streams) {
    report.clusters += stream.clusters;
    report.e_pi_morse = std::max(report.e_pi_morse, stream.e_pi_morse);
    report.e_pi = std::max(report.e_pi, stream.e_pi);
    report.ms_segmentation += stream.ms_segmentation;
    report.ms_motion += stream.ms_motion;
    report.ms_prediction += stream.ms_prediction;
    report.ms_rate_control += stream.ms_rate_control;
    report.ms_entropy += stream.ms_entropy;
  }
  return Status::Ok();
}

}  // namespace segmorph
