#include "encoding/primitive_encoding.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "common/stream_format.h"
#include "common/vertex_gather.h"
#include "decode/frame_decoder.h"
#include "encode/metrics.h"
#include "encoding/compress_primitives.h"

namespace segmorph {
namespace {

// Draco position bits when none are given: the base mesh's quantization step (its largest extent over 2^bits)
// about kBaseStepRatio times the residual step the error target implies; for an animation stream of F frames, F
// below kBaseStepFrames, times sqrt(kBaseStepFrames / F); at least kMinPositionBits (kMinKeptTargetBits for kept
// targets: 11 bits measured +0.2 to +0.4 % on AnimatedMorphSphere). The animation's closed loop corrects the base
// mesh's error, so the base need not be much finer than the residuals, while a coarser base costs
// residual bits (or error) in every frame: the base's share of the error pays for its bytes once, its cost in the
// animation grows with F, so a short sequence takes a coarser base. (Finer for long ones measured better on the
// cow, but 13 % larger on the scaling torus at 100k vertices x 300 frames, whose rate control then lands far below
// its error target: docs/codec.md, "The base mesh's precision".) Measured with stream version 4 on the three
// sequences at KG 0.5 and 0.15 %: the best whole file or within 1.7 % of it (the horse at 0.5 %, 10 bits against
// 9), except chicken at 0.15 % and the horse at 0.15 % (12 bits, 0.4 and 3.6 % above 11: the cow at 0.15 % takes
// 12 too, and 11 would cost it 5 %); below about 2 bits coarser than the best the animation's bytes climb steeply.
// The floor was 11 with version 3, whose residuals corrected the base's error in every frame; version 4 and 10 bits
// made every file that changed smaller (the floor at 9: the cow at 1 % 12 % larger). Rate targets and lossless
// streams keep Draco's usual 14 bits.
constexpr int kMinPositionBits = 10, kMinKeptTargetBits = 12, kMaxPositionBits = 24, kDefaultPositionBits = 14;
constexpr double kBaseStepRatio = 0.25, kBaseStepFrames = 48;
}  // namespace

int automatic_position_bits(const std::vector<float>& positions, const std::vector<FrameSequence>& clips,
                            const CodecSettings& settings, bool animation_stream) {
  if (settings.mode != RateMode::error || positions.empty()) return kDefaultPositionBits;
  float low[3], high[3];
  bounding_box(positions.data(), positions.size() / 3, low, high);
  const double extent = std::max({high[0] - low[0], high[1] - low[1], high[2] - low[2]});
  size_t frames = 0;
  for (const FrameSequence& clip : clips) frames += clip.frame_count;
  const double coarser =
      animation_stream ? std::max(1.0, std::sqrt(kBaseStepFrames / double(std::max<size_t>(frames, 1)))) : 1.0;
  const double step = expected_residual_step(clips, frame_spread(clips), settings.target) * kBaseStepRatio * coarser;
  if (!(extent > 0) || !(step > 0)) return kDefaultPositionBits;
  const double bits = std::round(std::log2(extent / step + 1));
  const int least = animation_stream ? kMinPositionBits : kMinKeptTargetBits;
  return int(std::clamp(bits, double(least), double(kMaxPositionBits)));
}

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
  const VertexGather to_decoded(encoding.source);
  std::vector<FrameSequence> reordered(clips.size());
  for (size_t c = 0; c < clips.size(); ++c) {
    const FrameSequence& clip = clips[c];
    FrameSequence& out = reordered[c];
    out.vertex_count = decoded.vertex_count;
    out.frame_count = clip.frame_count;
    out.times = clip.times;
    out.triangles = decoded.triangles;
    out.positions.resize(clip.frame_count * decoded.vertex_count * 3);
    for (size_t f = 0; f < clip.frame_count; ++f) to_decoded.gather(clip.frame(f), out.frame(f));
  }
  return reordered;
}

// Encodes `reordered` against the decoded base positions, then decodes the stream as a reader will (a few tens of
// milliseconds) and refuses a stream that does not give back the encoder's own reconstruction: versions 1 to 3,
// whose reconstruction is the encoder's closed loop. A version-4 stream's reconstruction is that stream decoded
// already (encode_animation), which a second decode would only repeat.
Status encode_stream(const std::vector<FrameSequence>& reordered, const CodecSettings& settings,
                     const std::string& what, PrimitiveEncoding& encoding) {
  const BaseMesh& decoded = encoding.decoded;
  encoding.report = StreamReport();
  const Status encoded = encode_animation(reordered, decoded.attributes[0].values, settings, encoding.stream,
                                          &encoding.report, &encoding.reconstruction);
  if (!encoded.ok()) return Status(encoded.code(), what + ": " + encoded.message());
  const size_t version_at = sizeof(format::kMagic);
  if (encoding.stream.size() > version_at && encoding.stream[version_at] == format::kTransformVersion)
    return Status::Ok();
  if (settings.progress) settings.progress("checking that the stream decodes to the encoder's frames", -1);
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

}  // namespace segmorph
