// What encoding a primitive takes, shared by the frames' encode (baked_primitives.cpp) and the kept targets'
// (kept_targets.cpp): the base mesh through Draco (its precision, copies merged, the vertex order Draco gives back),
// the frames through the codec, checked by decoding them, and the written primitive.
#pragma once

#include <tiny_gltf.h>

#include <string>
#include <vector>

#include "accessor.h"
#include "draco_base_mesh.h"
#include "encode/encoder.h"
#include "encode/rate_target.h"
#include "segmorph_extension.h"

namespace segmorph {

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

// Draco position bits when none are given (the rule at kBaseStepRatio in primitive_encoding.cpp). animation_stream:
// the clips are the frames an animation stream codes against the base (its precision weighed against its error in
// each of them); false for kept targets (clips: the targets).
int automatic_position_bits(const std::vector<float>& positions, const std::vector<FrameSequence>& clips,
                            const CodecSettings& settings, bool animation_stream);

// Reads every attribute of `primitive` (POSITION first) and its triangles into a base mesh.
Status read_base_mesh(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                      const std::vector<uint32_t>& triangles, size_t vertex_count, const std::string& what,
                      BaseMesh& base);

// Compresses the base mesh, its copies of a vertex merged (merge_copies over `frames`), and finds which original
// vertex each vertex Draco gives back stands for; adds the time taken to `milliseconds`.
Status encode_base(const BaseMesh& base, const std::vector<FrameSequence>& frames, PrimitiveEncoding& out,
                   double& milliseconds);

// `clips` with their vertices in the order the decoder gets back from Draco.
std::vector<FrameSequence> in_decoded_order(const std::vector<FrameSequence>& clips, const PrimitiveEncoding& encoding);

// Encodes `reordered` against the decoded base positions, then decodes the stream as a reader will and refuses a
// stream that does not give back the encoder's own reconstruction.
Status encode_stream(const std::vector<FrameSequence>& reordered, const CodecSettings& settings,
                     const std::string& what, PrimitiveEncoding& encoding);

// The written primitive: attribute accessors without data (Draco holds it), the two extensions.
tinygltf::Primitive encoded_primitive(const tinygltf::Primitive& original, const PrimitiveEncoding& encoding,
                                      CompressedPrimitive compressed, AccessorWriter& writer);

}  // namespace segmorph
