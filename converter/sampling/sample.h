// Finding the animated primitives of a glTF scene and sampling them into frame sequences.
#pragma once

#include <tiny_gltf.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/frame_sequence.h"
#include "sampling/animation.h"
#include "segmorph/decoder.h"
#include "segmorph/segmorph.h"  // SampleSettings
#include "segmorph/status.h"

namespace segmorph {

// A node whose mesh's vertices move: its morph weights are animated, or its skin's joints are.
struct AnimatedNode {
  int node = -1;
  int mesh = -1;
  int skin = -1;         // -1 when not skinned
  bool morphed = false;  // the mesh has morph targets (animated or not, they are applied)
  bool weights_animated = false;
  bool skin_animated = false;
  std::vector<int> clips;  // indices into Scene::clips of the clips that move it

  // "morph", "skinned" or "morph+skinned".
  std::string kind() const;
};

struct Scene {
  std::vector<Clip> clips;  // every animation of the file, in file order
  NodeGraph graph;
  std::vector<AnimatedNode> animated;  // in node order
};

// The name of node `node` of `model`, or "node N" when it has none.
std::string node_name(const tinygltf::Model& model, int node);

// Reads the animations and finds the animated nodes. Fails with nothing_to_do when nothing moves vertices.
Status analyze_scene(const tinygltf::Model& model, Scene& scene);

// One primitive of an animated node, sampled over every clip that moves the node.
struct SampledPrimitive {
  int primitive = -1;                 // index in the mesh's primitives
  std::vector<float> rest_positions;  // V × 3, the POSITION attribute as stored
  std::vector<float> rest_normals;    // V × 3 unit normals, empty when the primitive has no NORMAL
  std::vector<float> rest_tangents;   // V × 4, empty when the primitive has no TANGENT
  std::vector<std::vector<float>> target_deltas;  // per morph target: V × 3 POSITION displacements (empty: none)
  std::vector<FrameSequence> clips;   // one per AnimatedNode::clips entry, same order
  // A decoded primitive's (decode): the decoder of its stream, which turns its normals as every runtime does
  // (AnimationDecoder::turn_normals); null for a sampled one, whose normals bake turns itself.
  std::shared_ptr<AnimationDecoder> normals;
};

// Reads `primitive`'s POSITION (VEC3), NORMAL (VEC3) and TANGENT (VEC4) into out's rest_* fields, checking that
// normals and tangents have one element per vertex (baking reads them so). `what` names the primitive in errors.
Status read_rest_attributes(const tinygltf::Model& model, const tinygltf::Primitive& primitive, const std::string& what,
                            SampledPrimitive& out);

// The triangles of `primitive` (of `vertex_count` vertices): its TRIANGLES, or its strip or fan as triangles with
// their winding kept; none for points and lines. Indices beyond the vertex count fail, naming `what`.
Status read_triangles(const tinygltf::Model& model, const tinygltf::Primitive& primitive, size_t vertex_count,
                      const std::string& what, std::vector<uint32_t>& triangles);

// Positions under morph targets as glTF renders them: rest + Σ_t weights[t] × deltas[t] (deltas: per target V × 3,
// empty for a target without POSITION), in double: a float rest plus one float delta is exact, so one-hot
// sequences reproduce their frames bit for bit. out: V × 3.
void morph_positions(const std::vector<float>& rest, const std::vector<std::vector<float>>& deltas,
                     const double* weights, std::vector<double>& out);

struct SampledNode {
  const AnimatedNode* node = nullptr;
  std::vector<bool> clip_is_step;  // per clip: every track that moves the node uses STEP
  // Per clip: frame_count × target_count morph weights at the sampled times (empty without targets).
  std::vector<std::vector<double>> clip_weights;
  std::vector<SampledPrimitive> primitives;
};

// Frame times of `node` in clip `clip` (an index into scene.clips): sampling_times of the keys of the tracks that
// move it.
std::vector<float> frame_times(const Scene& scene, const tinygltf::Model& model, const AnimatedNode& node, int clip,
                               const SampleSettings& settings);

// Refuses, naming the node and clip, a sampling at settings.fps that would give a clip more than
// SampleSettings::kMaxGridFrames frames (a key hours away from the others). Without fps the frames are the keys,
// or a grid coarser than them.
Status check_frame_counts(const tinygltf::Model& model, const Scene& scene, const SampleSettings& settings);

// The times to sample at from the key times `keys` of the tracks that move something: the keys (sorted, each once)
// while they come at most SampleSettings::kMaxKeyRate a second, else a regular grid at kDefaultFps from the first
// to the last; with settings.fps, always a grid at that rate. Empty without keys.
std::vector<float> sampling_times(std::vector<float> keys, const SampleSettings& settings);

// Samples every primitive of `node` over its clips. Positions are in the node's mesh space for morph-only
// nodes and in model (world) space for skinned ones, as glTF renders them. `clip_times`, when given, holds
// per entry of node.clips the times to sample at instead of frame_times() (verify samples a second file
// at the first one's frame times).
Status sample_node(const tinygltf::Model& model, const Scene& scene, const AnimatedNode& node,
                   const SampleSettings& settings, SampledNode& out,
                   const std::vector<std::vector<float>>* clip_times = nullptr);

}  // namespace segmorph
