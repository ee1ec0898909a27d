// Animated primitives into SEGMORPH_animation_compression: each baked primitive's morph targets become a Draco base
// mesh and an animation stream (baked_primitives.cpp), and primitives that keep their morph targets code them as one
// stream (kept_targets.cpp). Reading them back is decoding/decode_file.h's.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "draco_base_mesh.h"
#include "encode/encoder.h"
#include "sampling/sample.h"
#include "segmorph/segmorph.h"
#include "segmorph/status.h"

namespace segmorph {

struct CompressReport {
  std::vector<StreamReport> primitives;  // one per encoded primitive
  size_t draco_bytes = 0, animation_bytes = 0;
  double ms_draco = 0;  // the base meshes: Draco encoding, the decoding the encoder needs, the vertex map back
};

// The codec's progress on a primitive (`what`: "mesh 1 primitive 0") as lines through `progress`, "mesh 1 primitive
// 0: rate control: measuring 12 steps (40 %)": nothing for the first kCodecQuietSeconds (a primitive encoded sooner
// says nothing more than the line that announced it), then each new stage as it starts and the fraction done of a
// stage at most every kCodecProgressSeconds.
constexpr double kCodecQuietSeconds = 2.0, kCodecProgressSeconds = 2.0;
// `clock`: seconds on a monotonic clock (the steady clock when empty; tests give their own).
CodecProgress codec_progress(const std::function<void(const std::string&)>& progress, const std::string& what,
                             std::function<double()> clock = {});

// `model` has just been baked (bake_model) from `sampled`. Replaces each baked primitive's morph targets by a
// Draco base mesh and an animation stream encoded with `settings`.
Status compress_model(tinygltf::Model& model, const std::vector<const SampledNode*>& sampled,
                      const CodecSettings& settings,
                      const DracoSettings& draco, CompressReport& report,
                      const std::function<void(const std::string&)>& progress);

// Compresses the morph-target meshes of `kept` (unskinned nodes, each the only user of its mesh; a lossy
// `settings`) where they are: each primitive's base mesh with Draco, its targets as one stream, the weights
// animation left as it is. The error target is that of the animation the weights play.
Status compress_targets(tinygltf::Model& model, const std::vector<const SampledNode*>& kept,
                        const CodecSettings& settings,
                        const DracoSettings& draco, CompressReport& report,
                        const std::function<void(const std::string&)>& progress);

// Copies of a vertex: vertices whose every base-mesh attribute and every position in `frames` are bit for bit
// equal. glTF files often store a vertex once per triangle that uses it (the Fox: 1728 vertices, 434 distinct),
// and Draco codes each copy. Returns the mesh of the distinct vertices, in order of first appearance, with the
// triangles renumbered; `first[m]` is the first original vertex of distinct vertex m. The primitive plays the
// same with one vertex in place of its copies. Two corners of one triangle are never merged.
BaseMesh merge_copies(const BaseMesh& base, const std::vector<FrameSequence>& frames, std::vector<uint32_t>& first);

}  // namespace segmorph
