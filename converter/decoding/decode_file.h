// Files with SEGMORPH_animation_compression read back into standard glTF (decode): Draco primitives into plain
// accessors, the streams through the runtime decoder, kept targets filled in, clips baked into the form bake writes.
#pragma once

#include <cstddef>
#include <vector>

#include <tiny_gltf.h>

#include "segmorph/segmorph.h"
#include "segmorph/status.h"

namespace segmorph {

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
// primitives. `threads`: for the Draco primitives and each version-4 stream's frames (AnimationDecoder::set_threads;
// 0: every hardware thread); the model written is the same for any.
Status decode_compressed_model(tinygltf::Model& model, DecodedSizes* sizes = nullptr,
                               std::vector<DecodedFrames>* decoded = nullptr, size_t threads = 1);

// decode_compressed_model for what measures positions only (the encoder's checks of its own output): the same
// POSITION data, without the normals a decoded stream's frames and kept targets would carry (no NORMAL morph targets
// are written; the rest NORMAL stays), which would cost a turn of every frame's normals.
Status decode_compressed_positions(tinygltf::Model& model, size_t threads = 1);

}  // namespace segmorph
