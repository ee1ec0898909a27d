// Primitives that keep their morph targets (compress_targets, compress_primitives.h): each target shape coded as a
// frame of one stream, its error target searched so that the animation the weights play meets the user's; the weights
// animations stay, in the smallest exact-enough form glTF allows.
#include <algorithm>
#include <cmath>

#include "bake/bake.h"
#include "encode/metrics.h"
#include "encoding/compress_primitives.h"
#include "encoding/primitive_encoding.h"
#include "segmorph_extension.h"

namespace segmorph {
namespace {

// Kept morph targets (compress_targets): at most kTargetRounds encodes, stopping once the animation's KG is within
// kCloseEnough (rate_target.h) of the goal; the targets' error target moves by at most kTargetsMaxRatio per round,
// a little further (kTargetsOvershootStep) when the last one was above the goal, and stays below kTargetsMaxError (%),
// which is reached when the weights hardly use the targets.
constexpr int kTargetRounds = 8;
constexpr double kTargetsMaxRatio = 3, kTargetsMaxError = 20, kTargetsOvershootStep = 0.97;

// The KG error (%) of the animation a primitive plays with its decoded targets, against `reordered`, the sampled
// original frames in the decoded vertex order.
double targets_kg_percent(const std::vector<FrameSequence>& reordered, const SampledNode& node,
                          const PrimitiveEncoding& encoding) {
  const std::vector<float>& base = encoding.decoded.attributes[0].values;
  const std::vector<std::vector<float>> deltas = target_displacements(encoding.reconstruction[0], base);
  ErrorAccumulator error;
  std::vector<double> morphed;
  for (size_t c = 0; c < reordered.size(); ++c) {
    FrameSequence played = reordered[c];
    for (size_t f = 0; f < played.frame_count; ++f) {
      // As sample_node plays them, which is how verify will measure the file.
      morph_positions(base, deltas, node.clip_weights[c].data() + f * deltas.size(), morphed);
      std::copy(morphed.begin(), morphed.end(), played.frame(f));
    }
    error.add(reordered[c], played);
  }
  return error.result().kg_percent;
}

Status compress_targets_node(tinygltf::Model& model, const SampledNode& node, const CodecSettings& settings,
                             const DracoSettings& draco, AccessorWriter& writer, CompressReport& report,
                             const std::function<void(const std::string&)>& progress) {
  const AnimatedNode& animated = *node.node;
  tinygltf::Mesh& mesh = model.meshes[size_t(animated.mesh)];
  size_t frame_total = 0;
  for (const FrameSequence& clip : node.primitives[0].clips) frame_total += clip.frame_count;
  for (size_t p = 0; p < mesh.primitives.size(); ++p) {
    tinygltf::Primitive& primitive = mesh.primitives[p];
    const SampledPrimitive& sampled = node.primitives[p];
    const std::string what = "mesh " + std::to_string(animated.mesh) + " primitive " + std::to_string(p);
    const FrameSequence& first = sampled.clips[0];
    if (first.triangles.empty())
      return Status(StatusCode::unsupported, what + ": only triangle primitives can be encoded");
    const size_t target_count = sampled.target_deltas.size(), values = first.vertex_count * 3;
    progress("encoding " + what + " (" + std::to_string(first.vertex_count) + " vertices, " +
             std::to_string(target_count) + " morph targets)");

    // The stream's one clip: frame t is the rest positions displaced by target t at weight 1.
    FrameSequence targets;
    targets.vertex_count = first.vertex_count;
    targets.frame_count = target_count;
    targets.triangles = first.triangles;
    targets.positions.resize(target_count * values);
    for (size_t t = 0; t < target_count; ++t) {
      targets.times.push_back(float(t));
      for (size_t i = 0; i < values; ++i)
        targets.positions[t * values + i] =
            sampled.rest_positions[i] + (sampled.target_deltas[t].empty() ? 0.0f : sampled.target_deltas[t][i]);
    }

    PrimitiveEncoding encoding;
    encoding.draco = draco;
    BaseMesh base;
    SEGMORPH_RETURN_IF_ERROR(read_base_mesh(model, primitive, first.triangles, first.vertex_count, what, base));
    if (encoding.draco.position_bits == 0)
      encoding.draco.position_bits = automatic_position_bits(base.attributes[0].values, {targets}, settings, false);
    SEGMORPH_RETURN_IF_ERROR(encode_base(base, {targets}, encoding, report.ms_draco));
    const std::vector<FrameSequence> reordered_targets = in_decoded_order({targets}, encoding);
    const std::vector<FrameSequence> reordered = in_decoded_order(sampled.clips, encoding);

    CodecSettings target_settings = settings;
    // Kept targets play as morph targets (their count is the file's, not the frames'), whatever their stream's
    // version: a GPU-playable setting would only make their stream larger.
    target_settings.gpu_playable = false;
    target_settings.outside_bytes += encoding.draco_bytes.size();
    target_settings.progress = codec_progress(progress, what);
    if (settings.mode == RateMode::bpvf) {
      // The rate is of the whole animation: its frames, not the targets, are what a vertex-frame counts, and
      // the primitive's vertices, not Draco's (copies merged, seams split).
      target_settings.target = settings.target * double(frame_total) / double(target_count) *
                               double(first.vertex_count) / double(encoding.decoded.vertex_count);
      SEGMORPH_RETURN_IF_ERROR(encode_stream(reordered_targets, target_settings, what, encoding));
    } else {
      // The error is of the animation the weights play, which mixes the targets' errors: the targets' error
      // target follows, by the ratio measured, until the animation's KG is within the (margined) target and not
      // far below it. A few encodes of T frames each.
      const double goal = settings.target * kErrorTargetMargin;
      double target = goal;
      PrimitiveEncoding best;
      bool found = false;
      for (int round = 0; round < kTargetRounds; ++round) {
        target_settings.target = target;
        SEGMORPH_RETURN_IF_ERROR(encode_stream(reordered_targets, target_settings, what, encoding));
        const double kg = targets_kg_percent(reordered, node, encoding);
        if (kg <= goal && (!found || encoding.stream.size() < best.stream.size())) {
          best = encoding;
          found = true;
        }
        if (found && kg >= kCloseEnough * goal) break;
        const double ratio = kg > 0 ? goal / kg : kTargetsMaxRatio;
        target = std::min(target * std::clamp(ratio * (kg > goal ? kTargetsOvershootStep : 1.0), 1 / kTargetsMaxRatio, kTargetsMaxRatio),
                          kTargetsMaxError);
        if (found && target <= target_settings.target) break;  // no coarser setting left to try
      }
      if (!found)
        return Status(StatusCode::internal, what + ": the morph targets did not reach the error target");
      encoding = std::move(best);
    }
    encoding.report.kg_percent = targets_kg_percent(reordered, node, encoding);  // of the animation, not the targets
    encoding.report.mesh = animated.mesh, encoding.report.primitive = int(p);
    report.primitives.push_back(encoding.report);
    report.draco_bytes += encoding.draco_bytes.size();
    report.animation_bytes += encoding.stream.size();

    // The targets stay, as accessors of zeros the stream fills in: POSITION, and NORMAL when the primitive has
    // normals and its targets moved them (the decoder derives them as bake does). Other target attributes go.
    const bool normals = primitive.attributes.count("NORMAL") &&
                         std::any_of(primitive.targets.begin(), primitive.targets.end(),
                                     [](const std::map<std::string, int>& t) { return t.count("NORMAL") > 0; });
    CompressedPrimitive compressed;
    compressed.morph_targets = true;
    tinygltf::Primitive out = encoded_primitive(primitive, encoding, compressed, writer);
    for (size_t t = 0; t < target_count; ++t) {
      std::map<std::string, int> target;
      target["POSITION"] = writer.add_zeros(encoding.decoded.vertex_count, TINYGLTF_TYPE_VEC3, true);
      if (normals) target["NORMAL"] = writer.add_zeros(encoding.decoded.vertex_count, TINYGLTF_TYPE_VEC3, false);
      out.targets.push_back(std::move(target));
    }
    primitive = std::move(out);
  }
  return Status::Ok();
}

}  // namespace

Status compress_targets(tinygltf::Model& model, const std::vector<const SampledNode*>& kept,
                        const CodecSettings& settings, const DracoSettings& draco, CompressReport& report,
                        const std::function<void(const std::string&)>& progress) {
  if (kept.empty()) return Status::Ok();
  if (settings.mode == RateMode::lossless)
    return Status(StatusCode::invalid_argument, "morph targets are kept only by lossy encodes");
  AccessorWriter writer(model);
  for (const SampledNode* kept_node : kept) {
    const SampledNode& node = *kept_node;
    const AnimatedNode& animated = *node.node;
    if (!animated.morphed || animated.skin >= 0)
      return Status(StatusCode::invalid_argument, "only the targets of unskinned morph meshes are kept");
    SEGMORPH_RETURN_IF_ERROR(compress_targets_node(model, node, settings, draco, writer, report, progress));
  }
  // The weights animations stay; their outputs take the smallest exact-enough form glTF allows: none when all
  // zero, normalized 16-bit integers when within [0, 1] or [−1, 1] (a weight off by at most 1/65535 of its
  // range moves a vertex by that fraction of its displacement), floats otherwise.
  std::vector<bool> weighted(model.nodes.size(), false);
  for (const SampledNode* node : kept) weighted[size_t(node->node->node)] = true;
  for (tinygltf::Animation& animation : model.animations) {
    std::vector<bool> done(animation.samplers.size(), false);
    for (const tinygltf::AnimationChannel& channel : animation.channels) {
      if (channel.target_path != "weights" || channel.target_node < 0 ||
          size_t(channel.target_node) >= weighted.size() || !weighted[size_t(channel.target_node)] ||
          channel.sampler < 0 || size_t(channel.sampler) >= done.size() || done[size_t(channel.sampler)])
        continue;
      done[size_t(channel.sampler)] = true;
      tinygltf::AnimationSampler& sampler = animation.samplers[size_t(channel.sampler)];
      std::vector<float> values;
      SEGMORPH_RETURN_IF_ERROR(read_floats(model, sampler.output, "weights output", values));
      const float low = values.empty() ? 0 : *std::min_element(values.begin(), values.end());
      const float high = values.empty() ? 0 : *std::max_element(values.begin(), values.end());
      if (low == 0 && high == 0)
        sampler.output = writer.add_zeros(values.size(), TINYGLTF_TYPE_SCALAR, false);
      else if (low >= -1 && high <= 1)
        sampler.output = writer.add_normalized_shorts(values.data(), values.size(), TINYGLTF_TYPE_SCALAR, low < 0);
    }
  }
  declare_extension(model, kDracoExtensionName, true);
  declare_extension(model, kExtensionName, false);
  return Status::Ok();
}

}  // namespace segmorph
