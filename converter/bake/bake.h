// The standard-glTF writer: animated primitives become morph targets played by one-hot weights animations.
//
// For every animated node, each frame of each clip that moves it becomes one morph target (POSITION deltas,
// and NORMAL deltas when the primitive has normals) of a new mesh whose base is the first frame of the
// node's first clip. Each clip gets a `weights` channel whose keys are the frame times and whose outputs are
// one-hot, stored as a sparse accessor (zero everywhere but one entry per key), so the weights cost
// O(frames) instead of O(frames²). Skinned nodes lose their skin: the baked mesh, in model space, goes on
// a new root node, and animation channels of joints that no longer move anything are removed. Everything
// else in the file is kept.
//
// Read back (base + 1 x delta in float), a frame is reproduced bit for bit whenever float addition can reach
// it from the base: always for sequences stored as base + delta (the classic compression sequences), and
// whenever a coordinate keeps its sign and stays within a factor 2 of the base. Elsewhere (a coordinate
// crossing zero while the base's is large) the sum moves in steps of the base's precision, and the frame is
// reproduced to within one ulp of the larger of the two magnitudes; no standard glTF encoding of a base plus
// deltas does better.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "sampling/sample.h"
#include "segmorph/status.h"

namespace segmorph {

// Replaces the animated nodes of `model` by their baked form. `sampled` holds one entry per node of
// scene.animated, in that order.
Status bake_model(tinygltf::Model& model, const Scene& scene, const std::vector<SampledNode>& sampled);

// The same for the nodes `sampled` points to (any of scene.animated). Without `write_frames`, each morph target is
// an accessor of zeros without data: the form an encode replaces by a stream at once (compress_model reads the
// baked base attributes and the clips' times, never the targets), without writing, and holding, every frame.
Status bake_model(tinygltf::Model& model, const Scene& scene, const std::vector<const SampledNode*>& sampled,
                  bool write_frames);

// The same bake, sampling one node at a time: sample(i, node) fills node i of scene.animated (from `model` as it is
// then: the nodes before it baked, its own data untouched) just before it is baked, and its frames are released
// after, so that the frames of one node are held at a time rather than the whole file's. `expected_bytes` (see
// baked_bytes) grows the buffer once to hold what the bake adds.
using NodeSampler = std::function<Status(size_t i, SampledNode& node)>;
Status bake_model(tinygltf::Model& model, const Scene& scene, const NodeSampler& sample, size_t expected_bytes = 0);

// At least what bake_model adds to the buffer of `model` when its animated nodes are sampled with `settings`: per
// primitive, the base POSITION, NORMAL and TANGENT and one POSITION (and NORMAL) delta per frame after the first,
// as floats, whether or not a delta turns out to be all zero; then a sixteenth more and 1 MB for the channels'
// keys, the views' alignment and the rest (room reserved and never written costs no memory).
size_t baked_bytes(const tinygltf::Model& model, const Scene& scene, const SampleSettings& settings);

// The index, in the file it was baked from, of a node bake_model wrote (extras.segmorph.source_node), or -1.
int source_node(const tinygltf::Node& node);

// Morph target displacements from decoded target frames: frame − base, as the decoder writes them.
std::vector<std::vector<float>> target_displacements(const FrameSequence& frames, const std::vector<float>& base);

}  // namespace segmorph
