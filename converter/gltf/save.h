// Writing whole glTF files (.gltf with a .bin beside it, or .glb), whole or not at all.
#pragma once

#include <cstddef>
#include <string>

#include <tiny_gltf.h>

#include "segmorph/status.h"

namespace segmorph {

// Writes `model` to `path` as repack would pack it, binary if it ends in .glb, JSON with a .bin beside it if it ends
// in .gltf: what nothing refers to is dropped from `model` (images given by URI move into bufferViews), and the one
// buffer's bytes are written view by view from where they lie, never copied into a buffer of their own (the model
// keeps its buffers). Numbers glTF defines as floats that hold a float exactly are written in the fewest digits that
// read back as that float. The files appear whole or not at all (output_file.h): a full disk or a signal leaves
// nothing.
Status save_gltf(tinygltf::Model& model, const std::string& path);

// The bytes save_gltf would write for `model` as a .glb (images that are files included as it embeds them).
size_t glb_size(tinygltf::Model model);

// Those bytes themselves (empty if the model cannot be written); `model` is repacked as save_gltf repacks it.
std::string glb_bytes(tinygltf::Model& model);

// Names segmorph and its version as the model's asset.generator ("segmorph 0.1.0"); a generator that was not
// segmorph's is kept as asset.extras.segmorph.input_generator.
void name_generator(tinygltf::Model& model);

}  // namespace segmorph
