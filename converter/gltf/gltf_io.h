// Loading and saving whole glTF files (.gltf with its resources, or .glb).
#pragma once

#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "segmorph/segmorph.h"
#include "segmorph/status.h"

namespace segmorph {

// Loads `path`. Images are kept as their encoded bytes (never decoded), so they pass through unchanged.
// Refuses what segmorph cannot read correctly: files whose geometry is compressed by an extension it does
// not decode. Non-fatal remarks of the parser go to `warnings`.
Status load_gltf(const std::string& path, tinygltf::Model& model, std::vector<std::string>* warnings = nullptr);

// Frees the bytes of the morph targets of the meshes `meshes` marks (one entry per mesh): their accessors keep their
// count, type and bounds but lose their data (glTF's all-zero form; an accessor something else also refers to keeps
// it), and each buffer shrinks to the views something still refers to, every index kept (a view nothing refers to
// is left empty, and saving drops it). For meshes whose frames are sampled and that are baked anyway: an encode then
// holds a long sequence of one-hot targets in its frames alone.
void release_target_data(tinygltf::Model& model, const std::vector<bool>& meshes);

// Drops meshes, skins, accessors, bufferViews and animation samplers nothing refers to, and packs all
// remaining data, embedded images included, into one buffer (in place, without a second buffer, when the views
// already lie in order in the first one).
void repack(tinygltf::Model& model);

// Writes `model` to `path` as repack would pack it, binary if it ends in .glb, JSON with a .bin beside it if it ends
// in .gltf: what nothing refers to is dropped from `model` (images given by URI move into bufferViews), and the one
// buffer's bytes are written view by view from where they lie, never copied into a buffer of their own (the model
// keeps its buffers). Numbers glTF defines as floats that hold a float exactly are written in the fewest digits that
// read back as that float. The files appear whole or not at all (output_file.h): a full disk or a signal leaves
// nothing.
Status save_gltf(tinygltf::Model& model, const std::string& path);

// The bytes save_gltf would write for `model` as a .glb (images that are files included as it embeds them).
size_t glb_size(tinygltf::Model model);

// An estimate of those bytes as a web server sends them, after a general-purpose compressor: each buffer view and the
// JSON at compressed_estimate(). For comparing two encodings of one file, not a prediction of brotli's output.
// `size`, when given, receives glb_size's figure (the file is written once for both).
size_t glb_delivered_estimate(tinygltf::Model model, size_t* size = nullptr);

// What a general-purpose compressor (brotli, gzip) might make of `count` bytes, cheaply: the least of the bytes
// themselves, their order-0 entropy as bytes, and their order-0 entropy as 32-bit words plus 4 bytes per distinct
// word (float data that repeats its values, as a weights animation's keys do, compresses far below its bytes'
// entropy). Entropy-coded data (animation streams, Draco) comes out at about its size.
double compressed_estimate(const unsigned char* data, size_t count);

// Names segmorph and its version as the model's asset.generator ("segmorph 0.1.0"); a generator that was not
// segmorph's is kept as asset.extras.segmorph.input_generator.
void name_generator(tinygltf::Model& model);

// has_gltf_extension(path) is declared in include/segmorph/segmorph.h.

}  // namespace segmorph
