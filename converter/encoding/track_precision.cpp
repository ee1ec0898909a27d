#include "encoding/track_precision.h"

#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "sampling/animation.h"

namespace segmorph {
namespace {

// The largest scale of a node's parent's static global transform (1 for a root): a translation moves the mesh
// by that much per unit.
double parent_scale(const NodeGraph& graph, const std::vector<Eigen::Matrix4d>& global, int node) {
  if (node < 0 || size_t(node) >= graph.parent.size() || graph.parent[size_t(node)] < 0) return 1;
  const double scale = largest_scale(global[size_t(graph.parent[size_t(node)])]);
  return scale > 0 && std::isfinite(scale) ? scale : 1;
}

}  // namespace

double scene_diagonal(const tinygltf::Model& model) {
  NodeGraph graph;
  if (!build_node_graph(model, graph).ok()) return 1;
  std::vector<Eigen::Matrix4d> global;
  evaluate_global_transforms(model, graph, nullptr, 0, global);
  Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY), high = Eigen::Vector3d::Constant(-INFINITY);
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    const int mesh = model.nodes[n].mesh;
    if (mesh < 0 || size_t(mesh) >= model.meshes.size()) continue;
    for (const tinygltf::Primitive& primitive : model.meshes[size_t(mesh)].primitives) {
      const auto position = primitive.attributes.find("POSITION");
      if (position == primitive.attributes.end() || position->second < 0 ||
          size_t(position->second) >= model.accessors.size())
        continue;
      const tinygltf::Accessor& accessor = model.accessors[size_t(position->second)];
      if (accessor.minValues.size() != 3 || accessor.maxValues.size() != 3) continue;
      for (int corner = 0; corner < 8; ++corner) {
        Eigen::Vector4d p(corner & 1 ? accessor.maxValues[0] : accessor.minValues[0],
                          corner & 2 ? accessor.maxValues[1] : accessor.minValues[1],
                          corner & 4 ? accessor.maxValues[2] : accessor.minValues[2], 1);
        // A skinned mesh ignores its node's transform; its bind pose is near enough for a scale.
        const Eigen::Vector3d q = model.nodes[n].skin >= 0 ? p.head<3>() : Eigen::Vector3d((global[n] * p).head<3>());
        low = low.cwiseMin(q);
        high = high.cwiseMax(q);
      }
    }
  }
  const double diagonal = (high - low).norm();
  return diagonal > 0 && std::isfinite(diagonal) ? diagonal : 1;
}

Status compress_tracks(tinygltf::Model& model, const TrackPrecision& precision, TrackReport& report) {
  if (!(precision.distance > 0)) return Status(StatusCode::invalid_argument, "track precision must be positive");
  NodeGraph graph;
  SEGMORPH_RETURN_IF_ERROR(build_node_graph(model, graph));
  std::vector<Eigen::Matrix4d> global;
  evaluate_global_transforms(model, graph, nullptr, 0, global);
  const double diagonal = precision.diagonal > 0 ? precision.diagonal : scene_diagonal(model);
  const auto step_of = [&](TrackPath path, int node) {
    switch (path) {
      case TrackPath::rotation:  // an angle error of about twice the step, at a lever of half the diagonal
        return precision.distance / diagonal;
      case TrackPath::scale:
        return 2 * precision.distance / diagonal;
      default:
        return precision.distance / parent_scale(graph, global, node);
    }
  };
  return code_track_streams(model, step_of, report);
}

}  // namespace segmorph
