// The JSON objects of SEGMORPH_animation_compression (and the part of KHR_draco_mesh_compression segmorph
// reads), as plain structs, read from and written to tinygltf values. spec/ has the normative text.
//
// On a mesh primitive whose first frame is stored as usual (segmorph writes it with KHR_draco_mesh_compression):
//   "SEGMORPH_animation_compression": {
//       "bufferView": 12,                       the animation stream
//       "clips": [ { "animation": 0,            the animation the clip's frames belong to
//                    "times": 31,               accessor: the frame times (float, one per frame)
//                    "interpolation": "LINEAR" } ] }   or "STEP"
// or, on a primitive that keeps its morph targets (their data is the stream's; the weights animation is kept):
//   "SEGMORPH_animation_compression": { "bufferView": 12, "morphTargets": true }
// On an animation whose keyframe samplers are coded (their input and output accessors have no data; the track stream
// fills them, spec/tracks.md):
//   "SEGMORPH_animation_compression": { "bufferView": 14, "samplers": [0, 1, 2] }
// On an animation channel that exists only so that its animation is not empty:
//   "SEGMORPH_animation_compression": { "placeholder": true }
#pragma once

#include <map>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "segmorph/status.h"

namespace segmorph {

constexpr const char* kExtensionName = "SEGMORPH_animation_compression";
constexpr const char* kDracoExtensionName = "KHR_draco_mesh_compression";

struct CompressedClip {
  int animation = -1;
  int times = -1;
  bool step = false;  // interpolation STEP (else LINEAR)
};

struct CompressedPrimitive {
  int buffer_view = -1;
  std::vector<CompressedClip> clips;  // empty when morph_targets
  // The stream holds one clip whose frame t is the primitive's positions under morph target t at weight 1.
  bool morph_targets = false;
};

struct CompressedAnimation {
  int buffer_view = -1;
  std::vector<int> samplers;  // the coded samplers, in stream order; at least one, each once
};

struct DracoPrimitive {
  int buffer_view = -1;
  std::map<std::string, int> attributes;  // semantic → Draco attribute id
};

// Parse the extension objects; bad_data with a one-line message when a member is missing or of the wrong type.
Status parse_compressed_primitive(const tinygltf::Value& value, CompressedPrimitive& out);
Status parse_draco_primitive(const tinygltf::Value& value, DracoPrimitive& out);
Status parse_compressed_animation(const tinygltf::Value& value, CompressedAnimation& out);
bool is_placeholder_channel(const tinygltf::AnimationChannel& channel);

tinygltf::Value compressed_primitive_value(const CompressedPrimitive& primitive);
tinygltf::Value draco_primitive_value(const DracoPrimitive& primitive);
tinygltf::Value compressed_animation_value(const CompressedAnimation& animation);
tinygltf::Value placeholder_value();

// The compressed primitives of mesh `mesh` (empty when it has none), parsed and checked against spec/README.md's
// validity rules about a mesh: every primitive compressed, each a triangle list (rule 1); all keeping morph targets or
// all playing the same clips (rule 2); a mesh that plays clips used by exactly one node, no node using it skinned
// (rule 3); each clip's animation existing and named once (rule 6). `node`: the one node of a mesh that plays clips
// (-1 for kept targets).
Status read_compressed_mesh(const tinygltf::Model& model, size_t mesh, std::vector<CompressedPrimitive>& primitives,
                            int& node);

// Adds `name` to extensionsUsed (and extensionsRequired when `required`), once; or removes it from both.
void declare_extension(tinygltf::Model& model, const std::string& name, bool required);
void undeclare_extension(tinygltf::Model& model, const std::string& name);
bool declares_extension(const tinygltf::Model& model, const std::string& name);

}  // namespace segmorph
