// Reading files with SEGMORPH_animation_compression back into standard glTF (decode_compressed_model, decode_file.h):
// Draco primitives into plain accessors, the streams through the runtime decoder, kept targets filled in, clips baked
// into the form bake writes.
#include "decoding/decode_file.h"

#include <algorithm>
#include <cmath>

#include "accessor.h"
#include "bake/bake.h"
#include "common/parallel.h"
#include "common/stream_format.h"
#include "draco_base_mesh.h"
#include "segmorph/decoder.h"
#include "segmorph_extension.h"
#include "track_streams.h"

namespace segmorph {
namespace {

// Decodes the stream of compressed `primitive` (its extension object parsed into `compressed`) against its base
// mesh with the runtime decoder (include/segmorph/decoder.h): `out` gets the rest attributes and the decoded clips,
// each with the primitive's triangles; `bytes` the stream's length. `frames` holds the frame count the file gives each
// clip (its times accessor, or for kept targets the target count), checked against the stream before anything is
// sized by them.
Status decode_primitive_stream(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                               const CompressedPrimitive& compressed, const std::vector<size_t>& frames,
                               const std::string& what, size_t threads, SampledPrimitive& out, size_t& bytes) {
  SEGMORPH_RETURN_IF_ERROR(read_rest_attributes(model, primitive, what, out));
  std::vector<uint32_t> triangles;
  if (primitive.indices < 0) return Status(StatusCode::bad_data, what + ": a compressed primitive needs indices");
  SEGMORPH_RETURN_IF_ERROR(read_uints(model, primitive.indices, what + " indices", triangles));
  if (triangles.size() % 3 != 0) return Status(StatusCode::bad_data, what + ": its indices are not triangles");
  for (uint32_t index : triangles)
    if (index >= out.rest_positions.size() / 3)
      return Status(StatusCode::bad_data, what + ": an index exceeds the vertex count");
  const unsigned char* data = nullptr;
  SEGMORPH_RETURN_IF_ERROR(buffer_view_bytes(model, compressed.buffer_view, what + " " + kExtensionName, &data, &bytes));
  AnimationDecoder decoder;
  decoder.set_threads(threads);
  auto failed = [&](const Status& status) { return Status(status.code(), what + ": " + status.message()); };
  Status status = decoder.open(data, bytes, out.rest_positions.data(), out.rest_positions.size() / 3,
                               triangles.data(), triangles.size());
  if (!status.ok()) return failed(status);
  if (compressed.morph_targets && (decoder.clip_count() != 1 || decoder.frame_count(0) != frames[0]))
    return Status(StatusCode::bad_data, what + ": the stream's frames disagree with the morph target count (" +
                                            std::to_string(decoder.total_frame_count()) + " in " +
                                            std::to_string(decoder.clip_count()) + " clips, " +
                                            std::to_string(frames[0]) + " targets)");
  if (decoder.clip_count() != frames.size())
    return Status(StatusCode::bad_data, what + ": the stream has " + std::to_string(decoder.clip_count()) +
                                            " clips, the extension names " + std::to_string(frames.size()));
  for (size_t c = 0; c < frames.size(); ++c)
    if (decoder.frame_count(c) != frames[c])
      return Status(StatusCode::bad_data, what + ": clip " + std::to_string(c) + " has " +
                                              std::to_string(decoder.frame_count(c)) + " frames in the stream and " +
                                              std::to_string(frames[c]) + " times");
  out.clips.assign(frames.size(), FrameSequence());
  for (size_t c = 0; c < frames.size(); ++c) {
    FrameSequence& clip = out.clips[c];
    clip.vertex_count = decoder.vertex_count();
    clip.frame_count = frames[c];
    clip.triangles = triangles;
    clip.positions.resize(decoder.clip_floats(c));
    status = decoder.decode_clip(c, clip.positions.data(), clip.positions.size());
    if (!status.ok()) return failed(status);
  }
  if (!out.rest_normals.empty()) out.normals = std::make_shared<AnimationDecoder>(std::move(decoder));
  return Status::Ok();
}

// What decode_compressed_model reports of a primitive's decoded clips.
DecodedFrames decoded_frames(int mesh, int primitive, bool targets, const std::vector<FrameSequence>& clips) {
  DecodedFrames out;
  out.mesh = mesh, out.primitive = primitive, out.targets = targets;
  for (const FrameSequence& clip : clips) out.clips.push_back({clip.vertex_count, clip.frame_count, clip.positions});
  return out;
}

// Decodes the stream of a primitive that keeps its morph targets and fills the targets in: POSITION with the
// decoded displacements, NORMAL (where the target has it) turned by the decoder (AnimationDecoder::turn_normals), or
// removed when not `with_normals`. `bytes`: the stream's length.
Status restore_targets(tinygltf::Model& model, tinygltf::Primitive& primitive, const CompressedPrimitive& compressed,
                       const std::string& what, size_t threads, bool with_normals, size_t& bytes,
                       std::vector<FrameSequence>* frames) {
  SampledPrimitive rest;
  if (primitive.targets.empty()) return Status(StatusCode::bad_data, what + ": it keeps morph targets but has none");
  SEGMORPH_RETURN_IF_ERROR(
      decode_primitive_stream(model, primitive, compressed, {primitive.targets.size()}, what, threads, rest, bytes));
  const std::vector<FrameSequence>& clips = rest.clips;
  const size_t vertex_count = rest.rest_positions.size() / 3;
  for (const std::map<std::string, int>& target : primitive.targets)
    for (const auto& [semantic, accessor] : target)
      if (semantic != "POSITION" && semantic != "NORMAL")
        return Status(StatusCode::bad_data, what + ": a kept morph target has " + semantic +
                                                ", which the stream does not restore");

  AccessorWriter writer(model);
  const std::vector<std::vector<float>> deltas = target_displacements(clips[0], rest.rest_positions);
  if (frames) {  // the displacements as one clip of T frames
    frames->assign(1, clips[0]);
    for (size_t t = 0; t < deltas.size(); ++t) std::copy(deltas[t].begin(), deltas[t].end(), (*frames)[0].frame(t));
  }
  const bool normals = !rest.rest_normals.empty();
  std::vector<float> frame_normals(vertex_count * 3), normal_delta(vertex_count * 3);
  for (size_t t = 0; t < deltas.size(); ++t) {
    std::map<std::string, int>& target = primitive.targets[t];
    if (!target.count("POSITION"))
      return Status(StatusCode::bad_data, what + ": a kept morph target has no POSITION");
    target["POSITION"] = writer.add_floats(deltas[t].data(), vertex_count, TINYGLTF_TYPE_VEC3, true, 0);
    if (!target.count("NORMAL")) continue;
    if (!normals) return Status(StatusCode::bad_data, what + ": a morph target has NORMAL, the primitive has none");
    if (!with_normals) {
      target.erase("NORMAL");
      continue;
    }
    const Status turned = rest.normals->turn_normals(rest.rest_normals.data(), clips[0].frame(t), 1,
                                                     frame_normals.data(), frame_normals.size());
    if (!turned.ok()) return Status(turned.code(), what + ": " + turned.message());
    for (size_t i = 0; i < normal_delta.size(); ++i) normal_delta[i] = frame_normals[i] - rest.rest_normals[i];
    target["NORMAL"] = writer.add_floats(normal_delta.data(), vertex_count, TINYGLTF_TYPE_VEC3, false, 0);
  }
  primitive.extensions.erase(kExtensionName);
  return Status::Ok();
}

// Writes a decoded Draco attribute as plain data into `accessor` (replaced by a new one). Joints become unsigned
// integers, as glTF requires; normalized integers (weights) stay integers of the type their accessor declares
// when Draco holds them at that width, so that they still sum exactly; everything else becomes floats.
Status write_decoded_attribute(const BaseMeshAttribute& attribute, const std::string& what, AccessorWriter& writer,
                               const tinygltf::Model& model, int& accessor) {
  const int declared_type = model.accessors[size_t(accessor)].componentType;
  const bool declared_normalized = model.accessors[size_t(accessor)].normalized;
  const int type = type_of_components(attribute.components);
  const size_t count = attribute.values.size() / size_t(attribute.components);
  const bool joints = attribute.semantic.rfind("JOINTS_", 0) == 0;
  const int width = attribute.type == AttributeType::uint8 ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE
                                                           : TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  if (joints || (attribute.type != AttributeType::float32 && attribute.normalized && declared_normalized &&
                 declared_type == width)) {
    std::vector<uint16_t> integers(attribute.values.size());
    for (size_t i = 0; i < integers.size(); ++i) {
      const float value = attribute.values[i];
      if (!(value >= 0 && value <= 65535 && value == std::floor(value)))
        return Status(StatusCode::bad_data, what + ": Draco's " + attribute.semantic + " holds a non-integer");
      integers[i] = uint16_t(value);
    }
    // Joints keep a declared byte width when they fit it.
    const bool bytes = declared_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                       std::all_of(integers.begin(), integers.end(), [](uint16_t v) { return v <= 255; });
    const int component_type = !joints ? width
                               : bytes ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE
                                       : TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    accessor = writer.add_unsigned_integers(integers, type, component_type, !joints, TINYGLTF_TARGET_ARRAY_BUFFER);
    return Status::Ok();
  }
  std::vector<float> values = attribute.values;
  if (attribute.type != AttributeType::float32 && attribute.normalized) {
    const float top = attribute.type == AttributeType::uint8 ? 255.0f : 65535.0f;
    for (float& value : values) value /= top;
  }
  accessor = writer.add_floats(values.data(), count, type, attribute.semantic == "POSITION", TINYGLTF_TARGET_ARRAY_BUFFER);
  return Status::Ok();
}

}  // namespace

StreamKind compressed_stream_kind(const tinygltf::Model& model, int mesh, int primitive) {
  StreamKind kind;
  if (mesh < 0 || size_t(mesh) >= model.meshes.size() || primitive < 0 ||
      size_t(primitive) >= model.meshes[size_t(mesh)].primitives.size())
    return kind;
  const auto& extensions = model.meshes[size_t(mesh)].primitives[size_t(primitive)].extensions;
  const auto found = extensions.find(kExtensionName);
  CompressedPrimitive compressed;
  const unsigned char* data = nullptr;
  size_t size = 0;
  if (found == extensions.end() || !parse_compressed_primitive(found->second, compressed).ok() ||
      !buffer_view_bytes(model, compressed.buffer_view, kExtensionName, &data, &size).ok() ||
      size <= sizeof(format::kMagic) || !std::equal(std::begin(format::kMagic), std::end(format::kMagic), data))
    return kind;
  kind.version = data[sizeof(format::kMagic)];
  kind.kept_targets = compressed.morph_targets;
  return kind;
}

Status decode_draco_primitives(tinygltf::Model& model, size_t threads) {
  // The primitives to decode, in order, up to the first that cannot be (its error comes after theirs).
  struct Job {
    tinygltf::Primitive* primitive;
    std::string what;
    DracoPrimitive draco;
    std::vector<unsigned char> bytes;  // copied: writing the decoded accessors may move the model's buffer
    BaseMesh decoded;
    Status status;
  };
  std::vector<Job> jobs;
  Status refused;
  for (size_t m = 0; m < model.meshes.size() && refused.ok(); ++m)
    for (size_t p = 0; p < model.meshes[m].primitives.size() && refused.ok(); ++p) {
      tinygltf::Primitive& primitive = model.meshes[m].primitives[p];
      auto it = primitive.extensions.find(kDracoExtensionName);
      if (it == primitive.extensions.end()) continue;
      Job job;
      job.primitive = &primitive;
      job.what = "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
      if (primitive.mode != -1 && primitive.mode != TINYGLTF_MODE_TRIANGLES) {
        refused = Status(StatusCode::unsupported,
                         job.what + ": only triangle primitives are read from KHR_draco_mesh_compression (mode " +
                             std::to_string(primitive.mode) + ")");
        break;
      }
      const unsigned char* data = nullptr;
      size_t size = 0;
      refused = parse_draco_primitive(it->second, job.draco);
      if (refused.ok())
        refused = buffer_view_bytes(model, job.draco.buffer_view, job.what + " " + kDracoExtensionName, &data, &size);
      if (!refused.ok()) break;
      job.bytes.assign(data, data + size);
      jobs.push_back(std::move(job));
    }
  // Decoded a batch at a time (each primitive on a thread of its own), then written in order.
  const size_t batch = thread_count(threads);
  AccessorWriter writer(model);
  for (size_t first = 0; first < jobs.size(); first += batch) {
    const size_t count = std::min(batch, jobs.size() - first);
    parallel_ranges(count, batch, [&](size_t begin, size_t end) {
      for (size_t j = first + begin; j < first + end; ++j) {
        Job& job = jobs[j];
        job.status = decode_draco_base_mesh(job.bytes.data(), job.bytes.size(), job.draco.attributes, job.decoded);
      }
    });
    for (size_t j = first; j < first + count; ++j) {
      Job& job = jobs[j];
      tinygltf::Primitive& primitive = *job.primitive;
      const BaseMesh& decoded = job.decoded;
      if (!job.status.ok()) return Status(job.status.code(), job.what + ": " + job.status.message());
      for (const BaseMeshAttribute& attribute : decoded.attributes) {
        auto accessor = primitive.attributes.find(attribute.semantic);
        if (accessor == primitive.attributes.end() || accessor->second < 0 ||
            size_t(accessor->second) >= model.accessors.size() ||
            model.accessors[size_t(accessor->second)].count != decoded.vertex_count)
          return Status(StatusCode::bad_data,
                        job.what + ": Draco's " + attribute.semantic + " disagrees with its accessor");
        SEGMORPH_RETURN_IF_ERROR(write_decoded_attribute(attribute, job.what, writer, model, accessor->second));
      }
      if (primitive.indices >= 0 && (size_t(primitive.indices) >= model.accessors.size() ||
                                     model.accessors[size_t(primitive.indices)].count != decoded.triangles.size()))
        return Status(StatusCode::bad_data, job.what + ": Draco's triangles disagree with the indices accessor");
      primitive.indices = writer.add_indices(decoded.triangles);
      primitive.mode = TINYGLTF_MODE_TRIANGLES;
      primitive.extensions.erase(kDracoExtensionName);
      job.decoded = BaseMesh();
      job.bytes = std::vector<unsigned char>();
    }
  }
  SEGMORPH_RETURN_IF_ERROR(refused);
  undeclare_extension(model, kDracoExtensionName);
  return Status::Ok();
}

namespace {

// The times of each clip of a compressed primitive, checked (FLOAT SCALAR, increasing): their counts, which the file's
// bytes back, are the frame counts the stream must have before anything is sized by it.
Status clip_times(const tinygltf::Model& model, const CompressedPrimitive& compressed, const std::string& what,
                  std::vector<std::vector<float>>& times) {
  times.assign(compressed.clips.size(), {});
  for (size_t c = 0; c < times.size(); ++c) {
    const int accessor = compressed.clips[c].times;
    if (accessor < 0 || size_t(accessor) >= model.accessors.size() ||
        model.accessors[size_t(accessor)].componentType != TINYGLTF_COMPONENT_TYPE_FLOAT ||
        model.accessors[size_t(accessor)].type != TINYGLTF_TYPE_SCALAR)
      return Status(StatusCode::bad_data, what + ": a clip's times must be a FLOAT SCALAR accessor");
    SEGMORPH_RETURN_IF_ERROR(read_floats(model, accessor, what + " clip times", times[c]));
    for (size_t f = 1; f < times[c].size(); ++f)
      if (!(times[c][f] > times[c][f - 1])) return Status(StatusCode::bad_data, what + ": clip times must increase");
  }
  return Status::Ok();
}

// The primitives of a mesh that plays clips, decoded into `node` (sampled as bake takes them; when not
// `with_normals`, with no rest normals, so that the frames are baked without them).
Status decode_clip_mesh(tinygltf::Model& model, const AnimatedNode& animated,
                        const std::vector<CompressedPrimitive>& streams, size_t threads, bool with_normals,
                        SampledNode& node, DecodedSizes& found, std::vector<DecodedFrames>* decoded) {
  node.node = &animated;
  tinygltf::Mesh& mesh = model.meshes[size_t(animated.mesh)];
  for (const CompressedClip& clip : streams[0].clips) node.clip_is_step.push_back(clip.step);
  for (size_t p = 0; p < mesh.primitives.size(); ++p) {
    tinygltf::Primitive& primitive = mesh.primitives[p];
    const std::string what = "mesh " + std::to_string(animated.mesh) + " primitive " + std::to_string(p);
    std::vector<std::vector<float>> times;
    SEGMORPH_RETURN_IF_ERROR(clip_times(model, streams[p], what, times));
    std::vector<size_t> frames;
    for (const std::vector<float>& clip : times) frames.push_back(clip.size());
    SampledPrimitive out;
    out.primitive = int(p);
    size_t bytes = 0;
    SEGMORPH_RETURN_IF_ERROR(decode_primitive_stream(model, primitive, streams[p], frames, what, threads, out, bytes));
    if (!with_normals) out.rest_normals.clear(), out.normals.reset();
    found.animation_bytes += bytes;
    ++found.primitives;
    for (size_t c = 0; c < out.clips.size(); ++c) out.clips[c].times = std::move(times[c]);
    if (decoded) decoded->push_back(decoded_frames(animated.mesh, int(p), false, out.clips));
    node.primitives.push_back(std::move(out));
    primitive.extensions.erase(kExtensionName);
  }
  return Status::Ok();
}

// The primitives of a mesh that keeps its morph targets, filled in.
Status decode_target_mesh(tinygltf::Model& model, size_t m, const std::vector<CompressedPrimitive>& primitives,
                          size_t threads, bool with_normals, DecodedSizes& found,
                          std::vector<DecodedFrames>* decoded) {
  for (size_t p = 0; p < primitives.size(); ++p) {
    size_t bytes = 0;
    std::vector<FrameSequence> displacements;
    SEGMORPH_RETURN_IF_ERROR(restore_targets(model, model.meshes[m].primitives[p], primitives[p],
                                             "mesh " + std::to_string(m) + " primitive " + std::to_string(p),
                                             threads, with_normals, bytes, decoded ? &displacements : nullptr));
    if (decoded) decoded->push_back(decoded_frames(int(m), int(p), true, displacements));
    found.animation_bytes += bytes;
    ++found.primitives;
  }
  return Status::Ok();
}

Status decode_compressed(tinygltf::Model& model, DecodedSizes* sizes, std::vector<DecodedFrames>* decoded,
                         size_t threads, bool with_normals) {
  SEGMORPH_RETURN_IF_ERROR(decode_draco_primitives(model, threads));
  if (!declares_extension(model, kExtensionName)) return Status::Ok();
  DecodedSizes found;
  SEGMORPH_RETURN_IF_ERROR(decode_tracks_in_model(model, &found.animation_bytes, &found.coded_animations));
  Scene scene;
  for (size_t a = 0; a < model.animations.size(); ++a) {
    scene.clips.emplace_back();
    SEGMORPH_RETURN_IF_ERROR(load_clip(model, int(a), scene.clips.back()));
  }
  // Kept targets are filled in where they are; a mesh that plays clips becomes an animated node to bake.
  std::vector<std::vector<CompressedPrimitive>> streams;
  for (size_t m = 0; m < model.meshes.size(); ++m) {
    std::vector<CompressedPrimitive> primitives;
    int user = -1;
    SEGMORPH_RETURN_IF_ERROR(read_compressed_mesh(model, m, primitives, user));
    if (primitives.empty()) continue;
    if (primitives[0].morph_targets) {
      SEGMORPH_RETURN_IF_ERROR(decode_target_mesh(model, m, primitives, threads, with_normals, found, decoded));
      continue;
    }
    AnimatedNode node;
    node.node = user;
    node.mesh = int(m);
    node.weights_animated = true;
    for (const CompressedClip& clip : primitives[0].clips) node.clips.push_back(clip.animation);
    scene.animated.push_back(node);
    streams.push_back(std::move(primitives));
  }
  std::vector<SampledNode> sampled(scene.animated.size());
  for (size_t i = 0; i < scene.animated.size(); ++i)
    SEGMORPH_RETURN_IF_ERROR(
        decode_clip_mesh(model, scene.animated[i], streams[i], threads, with_normals, sampled[i], found, decoded));
  for (tinygltf::Animation& animation : model.animations)
    animation.channels.erase(
        std::remove_if(animation.channels.begin(), animation.channels.end(), is_placeholder_channel),
        animation.channels.end());
  SEGMORPH_RETURN_IF_ERROR(bake_model(model, scene, sampled));
  undeclare_extension(model, kExtensionName);
  if (decoded)
    std::stable_sort(decoded->begin(), decoded->end(), [](const DecodedFrames& a, const DecodedFrames& b) {
      return a.mesh != b.mesh ? a.mesh < b.mesh : a.primitive < b.primitive;
    });
  if (sizes) *sizes = found;
  return Status::Ok();
}

}  // namespace

Status decode_compressed_model(tinygltf::Model& model, DecodedSizes* sizes, std::vector<DecodedFrames>* decoded,
                               size_t threads) {
  return decode_compressed(model, sizes, decoded, threads, true);
}

Status decode_compressed_positions(tinygltf::Model& model, size_t threads) {
  return decode_compressed(model, nullptr, nullptr, threads, false);
}

}  // namespace segmorph
