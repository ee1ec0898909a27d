// Meshes that move with their nodes and need no animation stream, compressed as they are with
// KHR_draco_mesh_compression: skinned meshes whose skin encode keeps (the joints' tracks play them), and rigid
// meshes of nodes that animations move. Meshes that nothing moves pass through as they are.
#pragma once

#include <vector>

#include <tiny_gltf.h>

#include "draco_base_mesh.h"
#include "segmorph/status.h"

namespace segmorph {

// Per mesh of `model`: whether compress_moving_meshes takes it. A mesh qualifies when it has no morph targets,
// every primitive is a triangle list without extensions, and every node that uses it is either in `kept_skins`
// (node indices whose skin is kept) or moves rigidly: it or an ancestor is the target of a translation, rotation
// or scale channel, and it has no skin.
std::vector<bool> moving_meshes(const tinygltf::Model& model, const std::vector<int>& kept_skins);

struct MovingMeshReport {
  size_t primitives = 0, bytes = 0;
};

// Compresses each primitive of the meshes `meshes` marks with Draco: every attribute, joints as exact integers,
// weights as normalized bytes whose sum is exactly 255. `settings.position_bits` 0 chooses them per mesh: Draco's
// step about `step_ratio` times a spread, which puts the quantization's share of the KG error near
// 50 × step_ratio %. A skinned mesh's spread is its own (the RMS distance of its vertices from their centroid:
// the KG of the primitive divides by it); a rigid mesh's is `rigid_spread`, that of the whole it is a part of.
// The accessors keep their counts and POSITION its bounds, without data. Up to `threads` primitives are coded at once
// (0: every hardware thread), with the same model written for any number.
Status compress_moving_meshes(tinygltf::Model& model, const std::vector<bool>& meshes, const DracoSettings& settings,
                              double step_ratio, double rigid_spread, size_t threads, MovingMeshReport& report);

}  // namespace segmorph
