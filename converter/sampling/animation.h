// glTF 2.0 animation evaluation: samplers (STEP, LINEAR, CUBICSPLINE), node transforms and the node hierarchy.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <tiny_gltf.h>

#include "segmorph/status.h"

namespace segmorph {

enum class Interpolation { step, linear, cubic_spline };
enum class TargetPath { translation, rotation, scale, weights };

// One animation sampler with its data read and checked.
struct Curve {
  std::vector<float> times;   // K key times in seconds, non-decreasing
  std::vector<float> values;  // K × width, or K × 3 × width for CUBICSPLINE (in-tangent, value, out-tangent)
  int width = 0;              // components per key: 3 (translation, scale), 4 (rotation), target count (weights)
  Interpolation interpolation = Interpolation::linear;

  // Value at time t (clamped to the first and last keys) into out[0..width). Rotations are unit
  // quaternions (x, y, z, w) interpolated by shortest-path slerp, as the specification prescribes.
  void evaluate(double t, bool rotation, double* out) const;
};

struct Track {
  int node = -1;
  TargetPath path = TargetPath::translation;
  Curve curve;
};

struct Clip {
  int animation = -1;  // index in the glTF animations array
  std::string name;    // the animation's name, or "animation N" when it has none
  std::vector<Track> tracks;
};

// Reads and checks animation `index` of `model`: sampler and node indices, key times, output counts.
Status load_clip(const tinygltf::Model& model, int index, Clip& clip);

// The node hierarchy, checked to be a forest.
struct NodeGraph {
  std::vector<int> parent;  // -1 for roots
  std::vector<int> order;   // every node after its parent
};
Status build_node_graph(const tinygltf::Model& model, NodeGraph& graph);

// The largest scale of a transform: the longest of its first three columns' linear parts.
double largest_scale(const Eigen::Matrix4d& transform);

// Global transforms (column-major 4×4, model space) of every node at time t of `clip` (or the static
// pose when clip is null): animated TRS where the clip has a track, the node's own matrix or TRS elsewhere.
void evaluate_global_transforms(const tinygltf::Model& model, const NodeGraph& graph, const Clip* clip, double t,
                                std::vector<Eigen::Matrix4d>& global);

// evaluate_global_transforms' transform of `node` alone: its ancestors' products only, the same numbers.
Eigen::Matrix4d evaluate_global_transform(const tinygltf::Model& model, const NodeGraph& graph, const Clip* clip,
                                          double t, int node);

}  // namespace segmorph
