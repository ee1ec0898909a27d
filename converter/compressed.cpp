#include "compressed.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "accessor.h"
#include "bake.h"
#include "metrics.h"
#include "segmorph_extension.h"

namespace segmorph {
namespace {

int type_of_components(int components) {
  switch (components) {
    case 1:
      return TINYGLTF_TYPE_SCALAR;
    case 2:
      return TINYGLTF_TYPE_VEC2;
    case 3:
      return TINYGLTF_TYPE_VEC3;
    default:
      return TINYGLTF_TYPE_VEC4;
  }
}

// The codec's error target relative to the user's (see compress_model).
constexpr double kErrorTargetMargin = 0.99;

// Draco position bits when none are given: the base mesh's quantization step (its largest extent over 2^bits)
// about kBaseStepRatio times the residual step the error target implies, and at least kMinPositionBits. The
// animation's closed loop corrects the base mesh's error in every frame, so the base need not be much finer
// than the residuals, while a coarser base costs residual bits in every frame: measured on the three
// sequences at KG 0.5, 0.15 and 0.03 % (docs/codec.md), the best whole file is within a bit of this choice.
// Rate targets and lossless streams keep Draco's usual 14 bits.
constexpr int kMinPositionBits = 12, kMaxPositionBits = 24, kDefaultPositionBits = 14;
constexpr double kBaseStepRatio = 0.25;
int automatic_position_bits(const std::vector<float>& positions, const std::vector<FrameSequence>& clips,
                            const CodecSettings& settings) {
  if (settings.mode != RateMode::error || positions.empty()) return kDefaultPositionBits;
  float low[3], high[3];
  bounding_box(positions.data(), positions.size() / 3, low, high);
  const double extent = std::max({high[0] - low[0], high[1] - low[1], high[2] - low[2]});
  const double step = expected_residual_step(clips, frame_spread(clips), settings.target) * kBaseStepRatio;
  if (!(extent > 0) || !(step > 0)) return kDefaultPositionBits;
  const double bits = std::round(std::log2(extent / step + 1));
  return int(std::clamp(bits, double(kMinPositionBits), double(kMaxPositionBits)));
}

}  // namespace

Status compress_model(tinygltf::Model& model, const std::vector<SampledNode>& sampled, const CodecSettings& settings,
                      const DracoSettings& draco, CompressReport& report,
                      const std::function<void(const std::string&)>& progress) {
  AccessorWriter writer(model);
  for (const SampledNode& node : sampled) {
    const AnimatedNode& animated = *node.node;
    int host = -1;
    for (size_t n = 0; n < model.nodes.size(); ++n)
      if (source_node(model.nodes[n]) == animated.node && model.nodes[n].mesh >= 0) host = int(n);
    if (host < 0) return Status(StatusCode::invalid_argument, "compress_model needs a baked model");
    tinygltf::Mesh& mesh = model.meshes[size_t(model.nodes[size_t(host)].mesh)];

    // The clips of this node: each animation's weights channel on the host goes, its frame times stay.
    CompressedPrimitive compressed;
    for (size_t a = 0; a < model.animations.size(); ++a) {
      tinygltf::Animation& animation = model.animations[a];
      for (size_t c = 0; c < animation.channels.size(); ++c) {
        const tinygltf::AnimationChannel channel = animation.channels[c];
        if (channel.target_node != host || channel.target_path != "weights") continue;
        const tinygltf::AnimationSampler& sampler = animation.samplers[size_t(channel.sampler)];
        compressed.clips.push_back({int(a), sampler.input, sampler.interpolation == "STEP"});
        animation.channels.erase(animation.channels.begin() + long(c));
        if (animation.channels.empty()) {
          // A placeholder keeps the animation valid: the node's own translation, held over the clip.
          const tinygltf::Node& target = model.nodes[size_t(host)];
          const size_t frames = model.accessors[size_t(sampler.input)].count;
          std::vector<float> translation;
          for (size_t f = 0; f < frames; ++f)
            for (int k = 0; k < 3; ++k)
              translation.push_back(target.translation.size() == 3 ? float(target.translation[size_t(k)]) : 0.0f);
          tinygltf::AnimationSampler hold;
          hold.input = sampler.input;
          hold.interpolation = "STEP";
          // A node at the origin (the usual case) holds zeros, which need no data.
          const bool zero = std::all_of(translation.begin(), translation.end(), [](float x) { return x == 0; });
          hold.output = zero ? writer.add_zeros(frames, TINYGLTF_TYPE_VEC3, false)
                             : writer.add_floats(translation.data(), frames, TINYGLTF_TYPE_VEC3, false, 0);
          animation.samplers.push_back(hold);
          tinygltf::AnimationChannel placeholder;
          placeholder.sampler = int(animation.samplers.size()) - 1;
          placeholder.target_node = host;
          placeholder.target_path = "translation";
          placeholder.extensions[kExtensionName] = placeholder_value();
          animation.channels.push_back(placeholder);
        }
        break;
      }
    }
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
      BaseMesh base;
      base.vertex_count = frames.clips[0].vertex_count;
      base.triangles = frames.clips[0].triangles;
      for (const auto& [semantic, accessor] : primitive.attributes) {
        BaseMeshAttribute attribute;
        attribute.semantic = semantic;
        SEGMORPH_RETURN_IF_ERROR(
            read_floats(model, accessor, what + " " + semantic, attribute.values, &attribute.components));
        if (semantic == "POSITION")
          base.attributes.insert(base.attributes.begin(), std::move(attribute));
        else
          base.attributes.push_back(std::move(attribute));
      }
      DracoSettings primitive_draco = draco;
      if (primitive_draco.position_bits == 0)
        primitive_draco.position_bits = automatic_position_bits(base.attributes[0].values, frames.clips, settings);
      const auto draco_start = std::chrono::steady_clock::now();
      DracoPrimitive draco_primitive;
      std::vector<uint8_t> draco_bytes;
      SEGMORPH_RETURN_IF_ERROR(encode_draco_base_mesh(base, primitive_draco, draco_bytes, draco_primitive.attributes));
      BaseMesh decoded;
      SEGMORPH_RETURN_IF_ERROR(
          decode_draco_base_mesh(draco_bytes.data(), draco_bytes.size(), draco_primitive.attributes, decoded));
      // The frames in the order of the vertices the decoder gets back (Draco's edgebreaker reorders them, and may
      // merge duplicates; each decoded vertex follows the original it came from).
      std::vector<uint32_t> source;
      SEGMORPH_RETURN_IF_ERROR(match_decoded_vertices(base, decoded, primitive_draco, source));
      report.ms_draco +=
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - draco_start).count();
      std::vector<FrameSequence> reordered(frames.clips.size());
      for (size_t c = 0; c < frames.clips.size(); ++c) {
        const FrameSequence& clip = frames.clips[c];
        FrameSequence& out = reordered[c];
        out.vertex_count = decoded.vertex_count;
        out.frame_count = clip.frame_count;
        out.times = clip.times;
        out.triangles = decoded.triangles;
        out.positions.resize(clip.frame_count * decoded.vertex_count * 3);
        for (size_t f = 0; f < clip.frame_count; ++f)
          for (size_t v = 0; v < decoded.vertex_count; ++v)
            for (int k = 0; k < 3; ++k)
              out.positions[(f * decoded.vertex_count + v) * 3 + size_t(k)] =
                  clip.frame(f)[size_t(source[v]) * 3 + size_t(k)];
      }

      // The animation, against the base positions the decoder will have.
      CodecSettings primitive_settings = settings;
      primitive_settings.outside_bytes += draco_bytes.size();
      // The codec meets its error target on the frames it is given, in Draco's vertex order; verify measures
      // the decoded file against the original, where vertices Draco merged count once each and the morph-target
      // form adds its rounding (measured: up to 0.3 % above on the samples). Aim a little lower.
      if (settings.mode == RateMode::error) primitive_settings.target *= kErrorTargetMargin;
      std::vector<uint8_t> stream;
      EncodeReport encode_report;
      std::vector<FrameSequence> reconstruction, check;
      SEGMORPH_RETURN_IF_ERROR(encode_animation(reordered, decoded.attributes[0].values, primitive_settings, stream,
                                                &encode_report, &reconstruction));
      // Never write a stream a decoder would read differently: decode it as a reader will (a few tens of
      // milliseconds) and compare with the encoder's own reconstruction.
      const Status check_status =
          decode_animation(stream.data(), stream.size(), decoded.attributes[0].values, decoded.triangles, check);
      bool same = check_status.ok() && check.size() == reconstruction.size();
      for (size_t c = 0; same && c < check.size(); ++c) same = check[c].positions == reconstruction[c].positions;
      if (!same)
        return Status(StatusCode::internal, what + ": the animation stream does not decode to the encoder's frames (" +
                                                (check_status.ok() ? "different frames" : check_status.message()) +
                                                "); this is a segmorph bug, please report it");
      report.primitives.push_back(encode_report);
      report.draco_bytes += draco_bytes.size();
      report.animation_bytes += stream.size();

      // The primitive: attribute accessors without data (Draco holds it), the two extensions.
      tinygltf::Primitive out;
      out.material = primitive.material;
      out.mode = TINYGLTF_MODE_TRIANGLES;
      out.extras = primitive.extras;
      out.extensions = primitive.extensions;
      for (const BaseMeshAttribute& attribute : decoded.attributes) {
        const int type = type_of_components(attribute.components);
        // The data is Draco's; POSITION keeps its bounds, as glTF requires.
        out.attributes[attribute.semantic] =
            attribute.semantic == "POSITION" ? writer.add_described(attribute.values.data(), decoded.vertex_count, type)
                                             : writer.add_zeros(decoded.vertex_count, type, false);
      }
      // The indices accessor describes Draco's triangles and has no bufferView, as KHR_draco_mesh_compression
      // asks (validators warn about a TRIANGLES primitive whose vertex count is not a multiple of 3 without
      // one). tinygltf 2.7 refuses such accessors; load_gltf drops them before it parses (json_prepass.h).
      tinygltf::Accessor indices;
      indices.componentType =
          decoded.vertex_count <= 65535 ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
      indices.count = decoded.triangles.size();
      indices.type = TINYGLTF_TYPE_SCALAR;
      model.accessors.push_back(indices);
      out.indices = int(model.accessors.size()) - 1;
      draco_primitive.buffer_view = writer.add_view(draco_bytes.data(), draco_bytes.size(), 0);
      out.extensions[kDracoExtensionName] = draco_primitive_value(draco_primitive);
      CompressedPrimitive with_stream = compressed;
      with_stream.buffer_view = writer.add_view(stream.data(), stream.size(), 0);
      out.extensions[kExtensionName] = compressed_primitive_value(with_stream);
      primitive = std::move(out);
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

Status decode_draco_primitives(tinygltf::Model& model) {
  AccessorWriter writer(model);
  for (size_t m = 0; m < model.meshes.size(); ++m)
    for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
      tinygltf::Primitive& primitive = model.meshes[m].primitives[p];
      auto it = primitive.extensions.find(kDracoExtensionName);
      if (it == primitive.extensions.end()) continue;
      const std::string what = "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
      DracoPrimitive draco;
      SEGMORPH_RETURN_IF_ERROR(parse_draco_primitive(it->second, draco));
      const unsigned char* data = nullptr;
      size_t size = 0;
      SEGMORPH_RETURN_IF_ERROR(
          buffer_view_bytes(model, draco.buffer_view, what + " " + kDracoExtensionName, &data, &size));
      BaseMesh decoded;
      const Status status = decode_draco_base_mesh(data, size, draco.attributes, decoded);
      if (!status.ok()) return Status(status.code(), what + ": " + status.message());
      for (const BaseMeshAttribute& attribute : decoded.attributes) {
        auto accessor = primitive.attributes.find(attribute.semantic);
        if (accessor == primitive.attributes.end() || accessor->second < 0 ||
            size_t(accessor->second) >= model.accessors.size() ||
            model.accessors[size_t(accessor->second)].count != decoded.vertex_count)
          return Status(StatusCode::bad_data,
                        what + ": Draco's " + attribute.semantic + " disagrees with its accessor");
        const int type = type_of_components(attribute.components);
        if (attribute.semantic.rfind("JOINTS_", 0) == 0) {
          // glTF requires joints to be unsigned integers (files other tools compress, skinned ones, have them).
          std::vector<uint16_t> joints(attribute.values.size());
          for (size_t i = 0; i < joints.size(); ++i) {
            const float joint = attribute.values[i];
            if (!(joint >= 0 && joint <= 65535 && joint == std::floor(joint)))
              return Status(StatusCode::bad_data,
                            what + ": Draco's " + attribute.semantic + " holds a non-integer joint");
            joints[i] = uint16_t(joint);
          }
          accessor->second = writer.add_unsigned_shorts(joints, type, TINYGLTF_TARGET_ARRAY_BUFFER);
        } else {
          accessor->second = writer.add_floats(attribute.values.data(), decoded.vertex_count, type,
                                               attribute.semantic == "POSITION", TINYGLTF_TARGET_ARRAY_BUFFER);
        }
      }
      if (primitive.indices >= 0 && (size_t(primitive.indices) >= model.accessors.size() ||
                                     model.accessors[size_t(primitive.indices)].count != decoded.triangles.size()))
        return Status(StatusCode::bad_data, what + ": Draco's triangles disagree with the indices accessor");
      primitive.indices = writer.add_indices(decoded.triangles);
      primitive.mode = TINYGLTF_MODE_TRIANGLES;
      primitive.extensions.erase(it);
    }
  undeclare_extension(model, kDracoExtensionName);
  return Status::Ok();
}

Status decode_compressed_model(tinygltf::Model& model, DecodedSizes* sizes) {
  SEGMORPH_RETURN_IF_ERROR(decode_draco_primitives(model));
  if (!declares_extension(model, kExtensionName)) return Status::Ok();
  DecodedSizes found;

  Scene scene;
  for (size_t a = 0; a < model.animations.size(); ++a) {
    scene.clips.emplace_back();
    SEGMORPH_RETURN_IF_ERROR(load_clip(model, int(a), scene.clips.back()));
  }
  // One animated node per compressed mesh.
  std::vector<AnimatedNode>& animated = scene.animated;
  std::vector<std::vector<CompressedPrimitive>> streams;
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    std::vector<CompressedPrimitive> primitives;
    for (const tinygltf::Primitive& primitive : model.meshes[m].primitives) {
      auto it = primitive.extensions.find(kExtensionName);
      if (it == primitive.extensions.end()) continue;
      primitives.emplace_back();
      SEGMORPH_RETURN_IF_ERROR(parse_compressed_primitive(it->second, primitives.back()));
    }
    if (primitives.empty()) continue;
    const std::string what = "mesh " + std::to_string(m);
    if (primitives.size() != model.meshes[m].primitives.size())
      return Status(StatusCode::bad_data, what + ": some primitives are compressed and some are not");
    std::vector<int> users;
    for (size_t n = 0; n < model.nodes.size(); ++n)
      if (model.nodes[n].mesh == int(m)) users.push_back(int(n));
    if (users.size() != 1)
      return Status(StatusCode::bad_data, what + ": a compressed mesh must be used by exactly one node");
    AnimatedNode node;
    node.node = users[0];
    node.mesh = int(m);
    node.weights_animated = true;
    for (const CompressedClip& clip : primitives[0].clips) {
      if (size_t(clip.animation) >= model.animations.size())
        return Status(StatusCode::bad_data, what + ": a clip names an animation that does not exist");
      if (std::find(node.clips.begin(), node.clips.end(), clip.animation) != node.clips.end())
        return Status(StatusCode::bad_data, what + ": two clips name the same animation");
      node.clips.push_back(clip.animation);
    }
    // Validity rule 2 (spec/README.md): every primitive of the mesh has the same clips (each its own times).
    for (const CompressedPrimitive& other : primitives) {
      bool same = other.clips.size() == primitives[0].clips.size();
      for (size_t c = 0; same && c < other.clips.size(); ++c)
        same = other.clips[c].animation == primitives[0].clips[c].animation &&
               other.clips[c].step == primitives[0].clips[c].step;
      if (!same) return Status(StatusCode::bad_data, what + ": its primitives disagree on the clips");
    }
    animated.push_back(node);
    streams.push_back(std::move(primitives));
  }

  std::vector<SampledNode> sampled(animated.size());
  for (size_t i = 0; i < animated.size(); ++i) {
    SampledNode& node = sampled[i];
    node.node = &animated[i];
    tinygltf::Mesh& mesh = model.meshes[size_t(animated[i].mesh)];
    for (const CompressedClip& clip : streams[i][0].clips) node.clip_is_step.push_back(clip.step);
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      tinygltf::Primitive& primitive = mesh.primitives[p];
      const std::string what = "mesh " + std::to_string(animated[i].mesh) + " primitive " + std::to_string(p);
      SampledPrimitive out;
      out.primitive = int(p);
      SEGMORPH_RETURN_IF_ERROR(read_rest_attributes(model, primitive, what, out));
      std::vector<uint32_t> triangles;
      if (primitive.indices < 0) return Status(StatusCode::bad_data, what + ": a compressed primitive needs indices");
      SEGMORPH_RETURN_IF_ERROR(read_uints(model, primitive.indices, what + " indices", triangles));
      for (uint32_t index : triangles)
        if (index >= out.rest_positions.size() / 3)
          return Status(StatusCode::bad_data, what + ": an index exceeds the vertex count");

      const unsigned char* data = nullptr;
      size_t size = 0;
      SEGMORPH_RETURN_IF_ERROR(
          buffer_view_bytes(model, streams[i][p].buffer_view, what + " " + kExtensionName, &data, &size));
      found.animation_bytes += size;
      ++found.primitives;
      const Status status = decode_animation(data, size, out.rest_positions, triangles, out.clips);
      if (!status.ok()) return Status(status.code(), what + ": " + status.message());
      if (out.clips.size() != streams[i][p].clips.size())
        return Status(StatusCode::bad_data, what + ": the stream's clip count disagrees with the extension's");
      for (size_t c = 0; c < out.clips.size(); ++c) {
        FrameSequence& clip = out.clips[c];
        SEGMORPH_RETURN_IF_ERROR(read_floats(model, streams[i][p].clips[c].times, what + " clip times", clip.times));
        if (clip.times.size() != clip.frame_count)
          return Status(StatusCode::bad_data, what + ": a clip's times disagree with its frame count");
        for (size_t f = 1; f < clip.times.size(); ++f)
          if (!(clip.times[f] > clip.times[f - 1]))
            return Status(StatusCode::bad_data, what + ": clip times must increase");
        clip.triangles = triangles;
      }
      node.primitives.push_back(std::move(out));
      primitive.extensions.erase(kExtensionName);
    }
  }
  for (tinygltf::Animation& animation : model.animations)
    animation.channels.erase(
        std::remove_if(animation.channels.begin(), animation.channels.end(), is_placeholder_channel),
        animation.channels.end());
  SEGMORPH_RETURN_IF_ERROR(bake_model(model, scene, sampled));
  undeclare_extension(model, kExtensionName);
  if (sizes) *sizes = found;
  return Status::Ok();
}

}  // namespace segmorph
