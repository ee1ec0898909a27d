#include "compressed.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "accessor.h"
#include "bake.h"
#include "metrics.h"
#include "normals.h"
#include "segmorph/decoder.h"
#include "topology.h"
#include "segmorph_extension.h"
#include "tracks.h"

namespace segmorph {

BaseMesh merge_copies(const BaseMesh& base, const std::vector<FrameSequence>& frames, std::vector<uint32_t>& first) {
  const size_t vertex_count = base.vertex_count;
  // What a vertex is made of, as columns of `width` floats per vertex: each attribute, then each frame's positions.
  struct Column {
    const float* values;
    size_t width;
  };
  std::vector<Column> columns;
  for (const BaseMeshAttribute& attribute : base.attributes)
    columns.push_back({attribute.values.data(), size_t(attribute.components)});
  for (const FrameSequence& clip : frames)
    for (size_t f = 0; f < clip.frame_count; ++f) columns.push_back({clip.frame(f), 3});
  // Each vertex's bits, hashed (FNV-1a over the 32-bit words); equal hashes are compared in full (only distinct
  // vertices whose hashes collide cost more than one comparison).
  std::vector<std::pair<uint64_t, uint32_t>> hashed(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    uint64_t hash = 0xcbf29ce484222325u;
    for (const Column& column : columns)
      for (size_t c = 0; c < column.width; ++c) {
        uint32_t bits;
        std::memcpy(&bits, &column.values[v * column.width + c], 4);
        hash = (hash ^ bits) * 0x100000001b3u;
      }
    hashed[v] = {hash, uint32_t(v)};
  }
  std::sort(hashed.begin(), hashed.end());
  auto same = [&](uint32_t a, uint32_t b) {
    for (const Column& column : columns)
      if (std::memcmp(&column.values[a * column.width], &column.values[b * column.width],
                      column.width * sizeof(float)) != 0)
        return false;
    return true;
  };
  std::vector<uint32_t> leader(vertex_count);
  for (size_t i = 0; i < vertex_count;) {
    size_t end = i;
    while (end < vertex_count && hashed[end].first == hashed[i].first) ++end;
    // Within a run of equal hashes (ascending vertex order), each vertex joins the first earlier one it equals.
    for (size_t j = i; j < end; ++j) {
      const uint32_t v = hashed[j].second;
      leader[v] = v;
      for (size_t k = i; k < j; ++k)
        if (leader[hashed[k].second] == hashed[k].second && same(hashed[k].second, v)) {
          leader[v] = hashed[k].second;
          break;
        }
    }
    i = end;
  }
  // Never two corners of one triangle: Draco drops a triangle with a repeated vertex, and with it a vertex that
  // only such triangles use (and its animation). A corner that would repeat another keeps its own vertex.
  for (size_t t = 0; t + 2 < base.triangles.size(); t += 3) {
    const uint32_t* corner = &base.triangles[t];
    for (int k = 1; k < 3; ++k)
      for (int j = 0; j < k; ++j)
        if (corner[k] != corner[j] && leader[corner[k]] == leader[corner[j]]) {
          // The one that is not the leader goes back to itself (nothing joined it, so nothing else moves).
          const uint32_t copy = leader[corner[k]] == corner[k] ? corner[j] : corner[k];
          leader[copy] = copy;
        }
  }
  std::vector<uint32_t> index(vertex_count);
  first.clear();
  for (size_t v = 0; v < vertex_count; ++v) {
    if (leader[v] == v) {
      index[v] = uint32_t(first.size());
      first.push_back(uint32_t(v));
    } else {
      index[v] = index[leader[v]];
    }
  }
  BaseMesh merged;
  merged.vertex_count = first.size();
  for (const BaseMeshAttribute& attribute : base.attributes) {
    BaseMeshAttribute out = attribute;
    const size_t components = size_t(attribute.components);
    out.values.resize(first.size() * components);
    for (size_t m = 0; m < first.size(); ++m)
      std::copy_n(&attribute.values[first[m] * components], components, &out.values[m * components]);
    merged.attributes.push_back(std::move(out));
  }
  merged.triangles.reserve(base.triangles.size());
  for (uint32_t v : base.triangles) merged.triangles.push_back(index[v]);
  return merged;
}

namespace {

// The codec's error target relative to the user's (see compress_model).
constexpr double kErrorTargetMargin = 0.99;

// Kept morph targets (compress_targets): at most kTargetRounds encodes, stopping once the animation's KG is within
// kTargetsCloseEnough of the goal; the targets' error target moves by at most kTargetsMaxRatio per round and stays
// below kTargetsMaxError (%), which is reached when the weights hardly use the targets.
constexpr int kTargetRounds = 8;
constexpr double kTargetsCloseEnough = 0.93, kTargetsMaxRatio = 3, kTargetsMaxError = 20;

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

// One primitive on its way out: its base mesh through Draco, its frames through the codec.
struct PrimitiveEncoding {
  DracoSettings draco;
  std::vector<uint8_t> draco_bytes, stream;
  DracoPrimitive draco_primitive;
  BaseMesh decoded;              // the base mesh as a loader gets it back from Draco
  std::vector<uint32_t> source;  // per decoded vertex, the original vertex it came from
  StreamReport report;
  std::vector<FrameSequence> reconstruction;  // what the stream decodes to, in the decoded vertex order
};

// Reads every attribute of `primitive` (POSITION first) and its triangles into a base mesh.
Status read_base_mesh(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                      const std::vector<uint32_t>& triangles, size_t vertex_count, const std::string& what,
                      BaseMesh& base) {
  base = BaseMesh();
  base.vertex_count = vertex_count;
  base.triangles = triangles;
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
  return Status::Ok();
}

// Compresses the base mesh, its copies of a vertex merged (merge_copies over `frames`), and finds which original
// vertex each vertex Draco gives back stands for; adds the time taken to `milliseconds`.
Status encode_base(const BaseMesh& base, const std::vector<FrameSequence>& frames, PrimitiveEncoding& out,
                   double& milliseconds) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<uint32_t> first;
  const BaseMesh merged = merge_copies(base, frames, first);
  SEGMORPH_RETURN_IF_ERROR(encode_draco_base_mesh(merged, out.draco, out.draco_bytes, out.draco_primitive.attributes));
  SEGMORPH_RETURN_IF_ERROR(decode_draco_base_mesh(out.draco_bytes.data(), out.draco_bytes.size(),
                                                  out.draco_primitive.attributes, out.decoded));
  // Draco's edgebreaker reorders vertices and may merge duplicates; each decoded vertex follows the original it
  // came from.
  SEGMORPH_RETURN_IF_ERROR(match_decoded_vertices(merged, out.decoded, out.draco, out.source));
  for (uint32_t& source : out.source) source = first[source];
  milliseconds += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return Status::Ok();
}

// `clips` with their vertices in the order the decoder gets back from Draco.
std::vector<FrameSequence> in_decoded_order(const std::vector<FrameSequence>& clips, const PrimitiveEncoding& encoding) {
  const BaseMesh& decoded = encoding.decoded;
  std::vector<FrameSequence> reordered(clips.size());
  for (size_t c = 0; c < clips.size(); ++c) {
    const FrameSequence& clip = clips[c];
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
              clip.frame(f)[size_t(encoding.source[v]) * 3 + size_t(k)];
  }
  return reordered;
}

// Encodes `reordered` against the decoded base positions, then decodes the stream as a reader will (a few tens of
// milliseconds) and refuses a stream that does not give back the encoder's own reconstruction.
Status encode_stream(const std::vector<FrameSequence>& reordered, const CodecSettings& settings,
                     const std::string& what, PrimitiveEncoding& encoding) {
  const BaseMesh& decoded = encoding.decoded;
  encoding.report = StreamReport();
  SEGMORPH_RETURN_IF_ERROR(encode_animation(reordered, decoded.attributes[0].values, settings, encoding.stream,
                                            &encoding.report, &encoding.reconstruction));
  std::vector<FrameSequence> check;
  const Status check_status = decode_animation(encoding.stream.data(), encoding.stream.size(),
                                               decoded.attributes[0].values, decoded.triangles, check);
  bool same = check_status.ok() && check.size() == encoding.reconstruction.size();
  for (size_t c = 0; same && c < check.size(); ++c) same = check[c].positions == encoding.reconstruction[c].positions;
  if (!same)
    return Status(StatusCode::internal, what + ": the animation stream does not decode to the encoder's frames (" +
                                            (check_status.ok() ? "different frames" : check_status.message()) +
                                            "); this is a segmorph bug, please report it");
  return Status::Ok();
}

// The written primitive: attribute accessors without data (Draco holds it), the two extensions.
tinygltf::Primitive encoded_primitive(const tinygltf::Primitive& original, const PrimitiveEncoding& encoding,
                                      CompressedPrimitive compressed, AccessorWriter& writer) {
  const BaseMesh& decoded = encoding.decoded;
  tinygltf::Primitive out;
  out.material = original.material;
  out.mode = TINYGLTF_MODE_TRIANGLES;
  out.extras = original.extras;
  out.extensions = original.extensions;
  for (const BaseMeshAttribute& attribute : decoded.attributes) {
    const int type = type_of_components(attribute.components);
    // The data is Draco's; POSITION keeps its bounds, as glTF requires.
    out.attributes[attribute.semantic] =
        attribute.semantic == "POSITION" ? writer.add_described(attribute.values.data(), decoded.vertex_count, type)
                                         : writer.add_zeros(decoded.vertex_count, type, false);
  }
  out.indices = writer.add_described_indices(decoded.triangles.size(), decoded.vertex_count);
  DracoPrimitive draco = encoding.draco_primitive;
  draco.buffer_view = writer.add_view(encoding.draco_bytes.data(), encoding.draco_bytes.size(), 0);
  out.extensions[kDracoExtensionName] = draco_primitive_value(draco);
  compressed.buffer_view = writer.add_view(encoding.stream.data(), encoding.stream.size(), 0);
  out.extensions[kExtensionName] = compressed_primitive_value(compressed);
  return out;
}

// Morph target displacements from decoded target frames: frame − base, as the decoder writes them.
std::vector<std::vector<float>> target_displacements(const FrameSequence& frames, const std::vector<float>& base) {
  std::vector<std::vector<float>> deltas(frames.frame_count, std::vector<float>(base.size()));
  for (size_t t = 0; t < frames.frame_count; ++t)
    for (size_t i = 0; i < base.size(); ++i) deltas[t][i] = frames.frame(t)[i] - base[i];
  return deltas;
}

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
      encoding.draco.position_bits = automatic_position_bits(base.attributes[0].values, {targets}, settings);
    SEGMORPH_RETURN_IF_ERROR(encode_base(base, {targets}, encoding, report.ms_draco));
    const std::vector<FrameSequence> reordered_targets = in_decoded_order({targets}, encoding);
    const std::vector<FrameSequence> reordered = in_decoded_order(sampled.clips, encoding);

    CodecSettings target_settings = settings;
    target_settings.outside_bytes += encoding.draco_bytes.size();
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
        if (found && kg >= kTargetsCloseEnough * goal) break;
        const double ratio = kg > 0 ? goal / kg : kTargetsMaxRatio;
        target = std::min(target * std::clamp(ratio * (kg > goal ? 0.97 : 1.0), 1 / kTargetsMaxRatio, kTargetsMaxRatio),
                          kTargetsMaxError);
        if (found && target <= target_settings.target) break;  // no coarser setting left to try
      }
      if (!found)
        return Status(StatusCode::internal, what + ": the morph targets did not reach the error target");
      encoding = std::move(best);
    }
    encoding.report.kg_percent = targets_kg_percent(reordered, node, encoding);  // of the animation, not the targets
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

// Decodes the stream of compressed `primitive` (its extension object parsed into `compressed`) against its base
// mesh with the runtime decoder (include/segmorph/decoder.h): `out` gets the rest attributes and the decoded clips,
// each with the primitive's triangles; `bytes` the stream's length. `frames` holds the frame count the file gives each
// clip (its times accessor, or for kept targets the target count), checked against the stream before anything is
// sized by them.
Status decode_primitive_stream(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                               const CompressedPrimitive& compressed, const std::vector<size_t>& frames,
                               const std::string& what, SampledPrimitive& out, size_t& bytes) {
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
// decoded displacements, NORMAL (where the target has it) derived as bake derives frame normals. `bytes`: the
// stream's length.
Status restore_targets(tinygltf::Model& model, tinygltf::Primitive& primitive, const CompressedPrimitive& compressed,
                       const std::string& what, size_t& bytes, std::vector<FrameSequence>* frames) {
  SampledPrimitive rest;
  if (primitive.targets.empty()) return Status(StatusCode::bad_data, what + ": it keeps morph targets but has none");
  SEGMORPH_RETURN_IF_ERROR(
      decode_primitive_stream(model, primitive, compressed, {primitive.targets.size()}, what, rest, bytes));
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
  WeldedTopology topology;
  std::vector<double> base_geometric;
  std::vector<float> frame_normals(vertex_count * 3), normal_delta(vertex_count * 3);
  if (normals) {
    topology = weld_topology(clips);
    base_geometric = welded_vertex_normals(rest.rest_positions.data(), topology);
  }
  for (size_t t = 0; t < deltas.size(); ++t) {
    std::map<std::string, int>& target = primitive.targets[t];
    if (!target.count("POSITION"))
      return Status(StatusCode::bad_data, what + ": a kept morph target has no POSITION");
    target["POSITION"] = writer.add_floats(deltas[t].data(), vertex_count, TINYGLTF_TYPE_VEC3, true, 0);
    if (!target.count("NORMAL")) continue;
    if (!normals) return Status(StatusCode::bad_data, what + ": a morph target has NORMAL, the primitive has none");
    deform_normals(base_geometric, rest.rest_normals.data(), clips[0].frame(t), topology, frame_normals.data());
    for (size_t i = 0; i < normal_delta.size(); ++i) normal_delta[i] = frame_normals[i] - rest.rest_normals[i];
    target["NORMAL"] = writer.add_floats(normal_delta.data(), vertex_count, TINYGLTF_TYPE_VEC3, false, 0);
  }
  primitive.extensions.erase(kExtensionName);
  return Status::Ok();
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
    int matrix_stand_in = -1;  // the placeholders' node when the host has a matrix
    for (size_t a = 0; a < model.animations.size(); ++a) {
      tinygltf::Animation& animation = model.animations[a];
      for (size_t c = 0; c < animation.channels.size(); ++c) {
        const tinygltf::AnimationChannel channel = animation.channels[c];
        if (channel.target_node != host || channel.target_path != "weights") continue;
        const tinygltf::AnimationSampler& sampler = animation.samplers[size_t(channel.sampler)];
        compressed.clips.push_back({int(a), sampler.input, sampler.interpolation == "STEP"});
        animation.channels.erase(animation.channels.begin() + long(c));
        if (animation.channels.empty()) {
          // A placeholder keeps the animation valid: the node's own translation, held over the clip. A node
          // with a matrix cannot be animated; an empty child of it, made for the purpose, holds still instead.
          int placeholder_node = host;
          if (!model.nodes[size_t(host)].matrix.empty()) {
            if (matrix_stand_in < 0) {
              tinygltf::Node stand_in;
              stand_in.name = "segmorph placeholder";
              model.nodes.push_back(stand_in);
              matrix_stand_in = int(model.nodes.size()) - 1;
              model.nodes[size_t(host)].children.push_back(matrix_stand_in);
            }
            placeholder_node = matrix_stand_in;
          }
          const tinygltf::Node& target = model.nodes[size_t(placeholder_node)];
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
          placeholder.target_node = placeholder_node;
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
      PrimitiveEncoding encoding;
      encoding.draco = draco;
      BaseMesh base;
      SEGMORPH_RETURN_IF_ERROR(
          read_base_mesh(model, primitive, frames.clips[0].triangles, frames.clips[0].vertex_count, what, base));
      if (encoding.draco.position_bits == 0)
        encoding.draco.position_bits = automatic_position_bits(base.attributes[0].values, frames.clips, settings);
      SEGMORPH_RETURN_IF_ERROR(encode_base(base, frames.clips, encoding, report.ms_draco));

      // The animation, against the base positions the decoder will have.
      CodecSettings primitive_settings = settings;
      primitive_settings.outside_bytes += encoding.draco_bytes.size();
      // The codec meets its error target on the frames it is given, in Draco's vertex order; verify measures
      // the decoded file against the original, where vertices Draco merged count once each and the morph-target
      // form adds its rounding (measured: up to 0.3 % above on the samples). Aim a little lower.
      if (settings.mode == RateMode::error) primitive_settings.target *= kErrorTargetMargin;
      // A rate counts the primitive's vertices, not Draco's (copies merged, seams split).
      if (settings.mode == RateMode::bpvf)
        primitive_settings.target *= double(frames.clips[0].vertex_count) / double(encoding.decoded.vertex_count);
      SEGMORPH_RETURN_IF_ERROR(encode_stream(in_decoded_order(frames.clips, encoding), primitive_settings, what, encoding));
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

Status compress_targets(tinygltf::Model& model, const std::vector<SampledNode>& kept, const CodecSettings& settings,
                        const DracoSettings& draco, CompressReport& report,
                        const std::function<void(const std::string&)>& progress) {
  if (kept.empty()) return Status::Ok();
  if (settings.mode == RateMode::lossless)
    return Status(StatusCode::invalid_argument, "morph targets are kept only by lossy encodes");
  AccessorWriter writer(model);
  for (const SampledNode& node : kept) {
    const AnimatedNode& animated = *node.node;
    if (!animated.morphed || animated.skin >= 0)
      return Status(StatusCode::invalid_argument, "only the targets of unskinned morph meshes are kept");
    SEGMORPH_RETURN_IF_ERROR(compress_targets_node(model, node, settings, draco, writer, report, progress));
  }
  // The weights animations stay; their outputs take the smallest exact-enough form glTF allows: none when all
  // zero, normalized 16-bit integers when within [0, 1] or [−1, 1] (a weight off by at most 1/65535 of its
  // range moves a vertex by that fraction of its displacement), floats otherwise.
  std::vector<bool> weighted(model.nodes.size(), false);
  for (const SampledNode& node : kept) weighted[size_t(node.node->node)] = true;
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

Status decode_draco_primitives(tinygltf::Model& model) {
  AccessorWriter writer(model);
  for (size_t m = 0; m < model.meshes.size(); ++m)
    for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
      tinygltf::Primitive& primitive = model.meshes[m].primitives[p];
      auto it = primitive.extensions.find(kDracoExtensionName);
      if (it == primitive.extensions.end()) continue;
      const std::string what = "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
      if (primitive.mode != -1 && primitive.mode != TINYGLTF_MODE_TRIANGLES)
        return Status(StatusCode::unsupported,
                      what + ": only triangle primitives are read from KHR_draco_mesh_compression (mode " +
                          std::to_string(primitive.mode) + ")");
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
        SEGMORPH_RETURN_IF_ERROR(write_decoded_attribute(attribute, what, writer, model, accessor->second));
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

Status decode_compressed_model(tinygltf::Model& model, DecodedSizes* sizes, std::vector<DecodedFrames>* decoded) {
  SEGMORPH_RETURN_IF_ERROR(decode_draco_primitives(model));
  if (!declares_extension(model, kExtensionName)) return Status::Ok();
  DecodedSizes found;
  SEGMORPH_RETURN_IF_ERROR(decode_tracks_in_model(model, &found.animation_bytes, &found.coded_animations));

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
    for (const tinygltf::Primitive& primitive : model.meshes[m].primitives)
      if (primitive.mode != -1 && primitive.mode != TINYGLTF_MODE_TRIANGLES)
        return Status(StatusCode::bad_data, what + ": a compressed primitive must be a triangle list (mode 4)");
    for (const tinygltf::Node& node : model.nodes)
      if (node.mesh == int(m) && node.skin >= 0)
        return Status(StatusCode::bad_data, what + ": the node of a compressed mesh must not have a skin");
    const bool targets = primitives[0].morph_targets;
    for (const CompressedPrimitive& other : primitives)
      if (other.morph_targets != targets)
        return Status(StatusCode::bad_data, what + ": some primitives keep morph targets and some play clips");
    if (targets) {
      for (size_t p = 0; p < primitives.size(); ++p) {
        size_t bytes = 0;
        std::vector<FrameSequence> displacements;
        SEGMORPH_RETURN_IF_ERROR(restore_targets(model, model.meshes[m].primitives[p], primitives[p],
                                                 what + " primitive " + std::to_string(p), bytes,
                                                 decoded ? &displacements : nullptr));
        if (decoded) decoded->push_back(decoded_frames(int(m), int(p), true, displacements));
        found.animation_bytes += bytes;
        ++found.primitives;
      }
      continue;
    }
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
      // The clips' times first: their counts, which the file's bytes back, are the frame counts the stream must
      // have before anything is sized by it.
      std::vector<std::vector<float>> times(streams[i][p].clips.size());
      std::vector<size_t> frames;
      for (size_t c = 0; c < times.size(); ++c) {
        const int accessor = streams[i][p].clips[c].times;
        if (accessor < 0 || size_t(accessor) >= model.accessors.size() ||
            model.accessors[size_t(accessor)].componentType != TINYGLTF_COMPONENT_TYPE_FLOAT ||
            model.accessors[size_t(accessor)].type != TINYGLTF_TYPE_SCALAR)
          return Status(StatusCode::bad_data, what + ": a clip's times must be a FLOAT SCALAR accessor");
        SEGMORPH_RETURN_IF_ERROR(read_floats(model, accessor, what + " clip times", times[c]));
        for (size_t f = 1; f < times[c].size(); ++f)
          if (!(times[c][f] > times[c][f - 1]))
            return Status(StatusCode::bad_data, what + ": clip times must increase");
        frames.push_back(times[c].size());
      }
      SampledPrimitive out;
      out.primitive = int(p);
      size_t bytes = 0;
      SEGMORPH_RETURN_IF_ERROR(decode_primitive_stream(model, primitive, streams[i][p], frames, what, out, bytes));
      found.animation_bytes += bytes;
      ++found.primitives;
      for (size_t c = 0; c < out.clips.size(); ++c) out.clips[c].times = std::move(times[c]);
      if (decoded) decoded->push_back(decoded_frames(animated[i].mesh, int(p), false, out.clips));
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
  if (decoded)
    std::stable_sort(decoded->begin(), decoded->end(), [](const DecodedFrames& a, const DecodedFrames& b) {
      return a.mesh != b.mesh ? a.mesh < b.mesh : a.primitive < b.primitive;
    });
  if (sizes) *sizes = found;
  return Status::Ok();
}

}  // namespace segmorph
