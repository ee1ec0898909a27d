// Encoding animated primitives as frames (compress_model, compress_primitives.h): each baked primitive's base mesh
// through Draco and its clips through the codec, the weights channels that played them replaced by the extension's
// clips (and placeholder channels where an animation would be left empty).
#include "encoding/compress_primitives.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "accessor.h"
#include "bake/bake.h"
#include "encoding/primitive_encoding.h"
#include "segmorph_extension.h"

namespace segmorph {

namespace {

// A placeholder keeps an animation valid once its last channel is gone: the node's own translation, held over the
// clip whose `input` it is keyed at. A node with a matrix cannot be animated; an empty child of it, made for the
// purpose (`stand_in`, created once per host), holds still instead.
void add_placeholder(tinygltf::Model& model, tinygltf::Animation& animation, int host, int input, int& stand_in,
                     AccessorWriter& writer) {
  int placeholder_node = host;
  if (!model.nodes[size_t(host)].matrix.empty()) {
    if (stand_in < 0) {
      tinygltf::Node node;
      node.name = "segmorph placeholder";
      model.nodes.push_back(node);
      stand_in = int(model.nodes.size()) - 1;
      model.nodes[size_t(host)].children.push_back(stand_in);
    }
    placeholder_node = stand_in;
  }
  const tinygltf::Node& target = model.nodes[size_t(placeholder_node)];
  const size_t frames = model.accessors[size_t(input)].count;
  std::vector<float> translation;
  for (size_t f = 0; f < frames; ++f)
    for (int k = 0; k < 3; ++k)
      translation.push_back(target.translation.size() == 3 ? float(target.translation[size_t(k)]) : 0.0f);
  tinygltf::AnimationSampler hold;
  hold.input = input;
  hold.interpolation = "STEP";
  // A node at the origin (the usual case) holds zeros, which need no data.
  const bool zero = std::all_of(translation.begin(), translation.end(), [](float x) { return x == 0; });
  hold.output = zero ? writer.add_zeros(frames, TINYGLTF_TYPE_VEC3, false)
                     : writer.add_floats(translation.data(), frames, TINYGLTF_TYPE_VEC3, false, 0);
  animation.samplers.push_back(hold);
  tinygltf::AnimationChannel placeholder;
  placeholder.sampler = int(animation.samplers.size()) - 1;
  placeholder.target_node = placeholder_node;
  placeholder.target_path = "translation";
  placeholder.extensions[kExtensionName] = placeholder_value();
  animation.channels.push_back(placeholder);
}

// The clips of baked node `host`: each animation's weights channel on it goes (a placeholder where that empties
// the animation), its frame times stay as the clip's times.
CompressedPrimitive take_clips(tinygltf::Model& model, int host, AccessorWriter& writer) {
  CompressedPrimitive compressed;
  int stand_in = -1;  // the placeholders' node when the host has a matrix
  for (size_t a = 0; a < model.animations.size(); ++a) {
    tinygltf::Animation& animation = model.animations[a];
    for (size_t c = 0; c < animation.channels.size(); ++c) {
      const tinygltf::AnimationChannel channel = animation.channels[c];
      if (channel.target_node != host || channel.target_path != "weights") continue;
      const tinygltf::AnimationSampler& sampler = animation.samplers[size_t(channel.sampler)];
      compressed.clips.push_back({int(a), sampler.input, sampler.interpolation == "STEP"});
      animation.channels.erase(animation.channels.begin() + long(c));
      if (animation.channels.empty()) add_placeholder(model, animation, host, sampler.input, stand_in, writer);
      break;
    }
  }
  return compressed;
}

}  // namespace

CodecProgress codec_progress(const std::function<void(const std::string&)>& progress, const std::string& what,
                             std::function<double()> clock) {
  if (!progress) return {};
  if (!clock)
    clock = [] { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); };
  struct Last {
    double start = 0, time = 0;  // the primitive's start, the last line's time
    std::string stage;           // the last stage reported
  };
  auto last = std::make_shared<Last>();  // the settings holding the callback are copied
  last->start = last->time = clock();
  return [progress, what, last, clock](const std::string& stage, double fraction) {
    const double now = clock();
    const bool quiet = now - last->start < kCodecQuietSeconds;
    const bool new_stage = stage != last->stage;
    last->stage = stage;
    if (quiet || (!new_stage && now - last->time < kCodecProgressSeconds)) return;
    last->time = now;
    std::string line = what + ": " + stage;
    if (fraction >= 0) line += " (" + std::to_string(int(std::floor(100 * std::min(fraction, 1.0)))) + " %)";
    progress(line);
  };
}

Status compress_model(tinygltf::Model& model, const std::vector<const SampledNode*>& sampled,
                      const CodecSettings& settings, const DracoSettings& draco, CompressReport& report,
                      const std::function<void(const std::string&)>& progress) {
  AccessorWriter writer(model);
  for (const SampledNode* sampled_node : sampled) {
    const SampledNode& node = *sampled_node;
    const AnimatedNode& animated = *node.node;
    int host = -1;
    for (size_t n = 0; n < model.nodes.size(); ++n)
      if (source_node(model.nodes[n]) == animated.node && model.nodes[n].mesh >= 0) host = int(n);
    if (host < 0) return Status(StatusCode::invalid_argument, "compress_model needs a baked model");
    tinygltf::Mesh& mesh = model.meshes[size_t(model.nodes[size_t(host)].mesh)];

    // The clips of this node: each animation's weights channel on the host goes, its frame times stay.
    CompressedPrimitive compressed = take_clips(model, host, writer);
    if (compressed.clips.empty()) continue;  // a single frame: nothing to animate

    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      tinygltf::Primitive& primitive = mesh.primitives[p];
      const SampledPrimitive& frames = node.primitives[p];
      const std::string what =
          "mesh " + std::to_string(model.nodes[size_t(host)].mesh) + " primitive " + std::to_string(p);
      if (frames.clips[0].triangles.empty())
        return Status(StatusCode::unsupported, what + ": only triangle primitives can be encoded");
      progress("encoding " + what + " (" + std::to_string(frames.clips[0].vertex_count) + " vertices)");

      // The base mesh: every attribute of the baked primitive (its first frame), and the triangles.
      PrimitiveEncoding encoding;
      encoding.draco = draco;
      BaseMesh base;
      SEGMORPH_RETURN_IF_ERROR(
          read_base_mesh(model, primitive, frames.clips[0].triangles, frames.clips[0].vertex_count, what, base));
      if (encoding.draco.position_bits == 0)
        encoding.draco.position_bits = automatic_position_bits(base.attributes[0].values, frames.clips, settings, true);
      SEGMORPH_RETURN_IF_ERROR(encode_base(base, frames.clips, encoding, report.ms_draco));

      // The animation, against the base positions the decoder will have.
      CodecSettings primitive_settings = settings;
      primitive_settings.outside_bytes += encoding.draco_bytes.size();
      primitive_settings.progress = codec_progress(progress, what);
      // The codec meets its error target on the frames it is given, in Draco's vertex order; verify measures
      // the decoded file against the original, where vertices Draco merged count once each and the morph-target
      // form adds its rounding (measured: up to 0.3 % above on the samples). Aim a little lower.
      if (settings.mode == RateMode::error) primitive_settings.target *= kErrorTargetMargin;
      // A rate counts the primitive's vertices, not Draco's (copies merged, seams split).
      if (settings.mode == RateMode::bpvf)
        primitive_settings.target *= double(frames.clips[0].vertex_count) / double(encoding.decoded.vertex_count);
      SEGMORPH_RETURN_IF_ERROR(encode_stream(in_decoded_order(frames.clips, encoding), primitive_settings, what, encoding));
      encoding.report.mesh = model.nodes[size_t(host)].mesh, encoding.report.primitive = int(p);
      report.primitives.push_back(encoding.report);
      report.draco_bytes += encoding.draco_bytes.size();
      report.animation_bytes += encoding.stream.size();
      primitive = encoded_primitive(primitive, encoding, compressed, writer);
    }
    if (mesh.extras.IsObject() && mesh.extras.Has("targetNames")) {
      tinygltf::Value::Object extras = mesh.extras.Get<tinygltf::Value::Object>();
      extras.erase("targetNames");
      mesh.extras = extras.empty() ? tinygltf::Value() : tinygltf::Value(std::move(extras));
    }
  }
  declare_extension(model, kDracoExtensionName, true);
  declare_extension(model, kExtensionName, false);
  return Status::Ok();
}

}  // namespace segmorph
