// Files with SEGMORPH_animation_compression: writing them (encode) and reading them back into standard glTF
// (decode). encode = bake, then each baked primitive's morph targets become a Draco base mesh and an animation
// stream; decode = the reverse, through the same writer as bake.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "draco_base_mesh.h"
#include "encode/encoder.h"
#include "sample.h"
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

// Sizes of what decoding found.
struct DecodedSizes {
  size_t animation_bytes = 0;  // SEGMORPH streams
  size_t primitives = 0;
  size_t coded_animations = 0;  // animations whose tracks were coded
};

// What an encoded primitive's SEGMORPH_animation_compression stream is: its version (0 where the primitive has no
// stream, or its bufferView holds no stream header) and whether it keeps morph targets. A version-4 stream of clips
// plays on the GPU from its model (docs/runtime.md, "Playing the model").
struct StreamKind {
  int version = 0;
  bool kept_targets = false;
  bool gpu_playable() const { return version == 4 && !kept_targets; }
};
StreamKind compressed_stream_kind(const tinygltf::Model& model, int mesh, int primitive);

// Replaces KHR_draco_mesh_compression primitives by plain accessors (the first step of decode_compressed_model),
// decoding up to `threads` primitives at once (0: every hardware thread); the model written is the same for any.
Status decode_draco_primitives(tinygltf::Model& model, size_t threads = 1);

// Replaces KHR_draco_mesh_compression primitives by plain accessors, then decodes SEGMORPH_animation_compression
// primitives with the runtime decoder (include/segmorph/decoder.h): those that keep morph targets get them back, the
// others take the form bake writes. A model with neither is left as it is. `decoded`, when given, receives what each
// compressed primitive's stream decoded to (DecodedFrames, include/segmorph/segmorph.h), in the order of meshes and
// primitives.
Status decode_compressed_model(tinygltf::Model& model, DecodedSizes* sizes = nullptr,
                               std::vector<DecodedFrames>* decoded = nullptr);

}  // namespace segmorph
