// A primitive's base mesh (the first frame: positions, other attributes, triangles) compressed with Draco, in
// the form KHR_draco_mesh_compression stores it. The only file that sees Draco.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "segmorph/status.h"

namespace segmorph {

// How Draco stores an attribute: floats, quantized with the bits of their kind (DracoSettings), or unsigned
// integers, kept exactly (JOINTS_n; WEIGHTS_n as normalized integers). For integer types `values` hold the
// integers themselves (exact in a float up to 2^24), whether or not they are normalized.
enum class AttributeType { float32, uint8, uint16 };

struct BaseMeshAttribute {
  std::string semantic;       // glTF attribute name: POSITION, NORMAL, TANGENT, TEXCOORD_n, COLOR_n, _NAME
  int components = 0;         // 1 to 4
  std::vector<float> values;  // V × components
  AttributeType type = AttributeType::float32;
  bool normalized = false;  // integer types: the value read is the integer over its type's maximum
};

struct BaseMesh {
  size_t vertex_count = 0;                    // V
  std::vector<BaseMeshAttribute> attributes;  // POSITION first
  std::vector<uint32_t> triangles;            // T × 3
};

struct DracoSettings {
  // Quantization bits per attribute kind. Normals: 8, Draco's and gltfpack's default (10 measured 1.8 KB more
  // on CesiumMan's 3273 vertices, 0.7 % of its file). Texture coordinates: 12, gltfpack's default (Draco's is 10).
  int position_bits = 14;
  int normal_bits = 8;
  int texcoord_bits = 12;
  int color_bits = 8;
  int generic_bits = 12;
  // Draco's encoding and decoding speed, 0 (best compression) to 10. 0: the base mesh is decoded once per file, and
  // speed 0 measured 3.5 % (Fox), 8.5 % (cow) and 11.6 % (CesiumMan) smaller than Draco's default speed 5, and 1 %
  // larger on MorphStressTest.
  int speed = 0;
  // Draco's sequential encoding keeps the vertex order but compresses several times worse than edgebreaker,
  // which reorders (and may merge) vertices; match_decoded_vertices maps them back.
  bool keep_order = false;
  // Draco stores each distinct value of an attribute once, with a map from points to values: a mesh whose vertices
  // are split along seams (flat shading, texture seams) then codes the positions they share once.
  bool share_values = false;
};

// Encodes `mesh` into `bytes` (edgebreaker, or sequential when settings.keep_order). `attribute_ids` receives, per semantic, the Draco
// attribute id that KHR_draco_mesh_compression's "attributes" map names.
Status encode_draco_base_mesh(const BaseMesh& mesh, const DracoSettings& settings, std::vector<uint8_t>& bytes,
                              std::map<std::string, int>& attribute_ids);

// Decodes Draco bytes. `attribute_ids`: semantic → Draco attribute id, as in the glTF extension; every named
// attribute must be present. Refuses a mesh whose counts exceed `max_vertices` before building arrays.
Status decode_draco_base_mesh(const uint8_t* data, size_t size, const std::map<std::string, int>& attribute_ids,
                              BaseMesh& mesh, size_t max_vertices = size_t(1) << 26);

// For each vertex Draco decoded, the vertex of `original` it came from. Draco keeps the triangles: each decoded
// triangle is matched to the original triangle whose corners are nearest (within a quantization step, other
// attributes alike; among the 16 nearest originals of one of its corners), surest matches first, and each vertex
// comes from the original of the first triangle matched around it; a vertex in no matched triangle comes from the
// nearest original (one no other decoded vertex came from, when there is one). Fails when a decoded vertex has no
// original within the step.
Status match_decoded_vertices(const BaseMesh& original, const BaseMesh& decoded, const DracoSettings& settings,
                              std::vector<uint32_t>& source);

}  // namespace segmorph
