// Measuring the animation of one glTF file against another's (verify): which animated primitive of the
// other file plays which primitive of the reference, at which times and in which space, and the error
// metrics over all of them.
#pragma once

#include <tiny_gltf.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "encode/metrics.h"
#include "sampling/sample.h"
#include "segmorph/status.h"

namespace segmorph {

// One animated primitive of the reference and the primitive of the other file that plays it.
struct PrimitiveComparison {
  int node = -1, mesh = -1, primitive = -1;                    // in the reference
  int other_node = -1, other_mesh = -1, other_primitive = -1;  // in the other file
  ErrorMetrics metrics;  // V and F (all clips) are the reference's
};

struct AnimationComparison {
  std::vector<PrimitiveComparison> primitives;  // in the order of the reference's sampled nodes and primitives
  ErrorMetrics worst;        // per metric, the largest over the reference's animated primitives
  size_t vertices = 0;       // V of the reference, summed over its animated primitives
  size_t frames = 0;         // F of the reference's first animated primitive, summed over its clips
  double vertex_frames = 0;  // V × F summed over the reference's animated primitives and their clips
};

// Compares `other` (loaded and analyzed into `other_scene`) with the reference file, whose animated nodes
// are sampled in `reference` (one entry per reference_scene.animated).
//
// A reference node's counterpart is the node bake wrote from it (extras.segmorph.source_node); in a file
// without that provenance, each primitive's counterpart is the primitive of any node with a mesh whose
// trajectories are nearest (tools such as gltfpack reorder and re-parent nodes, merge primitives, drop
// vertices and drop tracks that move nothing). It plays the animations of the same names (else the same
// indices), sampled at the reference's frame times, and its positions are carried into the reference's
// sampling space through both nodes' static global transforms, which undoes a quantizing tool's
// dequantization transform (KHR_mesh_quantization). Vertices pair by trajectory (match_vertices). A failed
// Status is about `other`.
//
// `encoded_from_reference`: `other` is segmorph's encode of the reference (decoded), whose nodes keep their indices:
// a node that was not baked is paired with the node of the same index, without the search by trajectory.
// `matches`, when given, keeps each primitive's vertex pairing (by reference node and primitive) from one call to
// the next: a search that compares encodes differing only in their tracks pairs the vertices once. The reference's
// nodes are compared on up to `threads` threads (0: every hardware thread), with the same result for any number.
using VertexMatches = std::map<std::pair<int, size_t>, std::vector<uint32_t>>;
Status compare_animation(const tinygltf::Model& reference_model, const Scene& reference_scene,
                         const std::vector<SampledNode>& reference, const tinygltf::Model& other_model,
                         const Scene& other_scene, AnimationComparison& result, bool encoded_from_reference = false,
                         VertexMatches* matches = nullptr, size_t threads = 1);

// The errors of primitive `primitive` of the mesh of node `node` in `other_model`, segmorph's encode of the reference
// (decoded), whose nodes keep their indices, for a mesh that moves rigidly with its node (encode's "rigid" meshes,
// which analyze_scene does not sample): its positions in model space at the key times (as sampling_times takes them)
// of every clip that moves the node or an ancestor (the rest pose when none does), vertices paired by trajectory
// (Draco reorders them). The KG error divides by the part's own spread.
Status compare_rigid_primitive(const tinygltf::Model& reference_model, const Scene& reference_scene,
                               const tinygltf::Model& other_model, const Scene& other_scene, int node, int primitive,
                               ErrorMetrics& metrics);

}  // namespace segmorph
