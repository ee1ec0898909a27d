// What a glTF file weighs as a web server sends it, estimated cheaply (for the automatic choice between kept and baked
// morph targets, which compares two encodings of one file).
#pragma once

#include <cstddef>

#include <tiny_gltf.h>

namespace segmorph {

// An estimate of those bytes as a web server sends them, after a general-purpose compressor: each buffer view and the
// JSON at compressed_estimate(). For comparing two encodings of one file, not a prediction of brotli's output.
// `size`, when given, receives glb_size's figure (the file is written once for both).
size_t glb_delivered_estimate(tinygltf::Model model, size_t* size = nullptr);

// What a general-purpose compressor (brotli, gzip) might make of `count` bytes, cheaply: the least of the bytes
// themselves, their order-0 entropy as bytes, and their order-0 entropy as 32-bit words plus 4 bytes per distinct
// word (float data that repeats its values, as a weights animation's keys do, compresses far below its bytes'
// entropy). Entropy-coded data (animation streams, Draco) comes out at about its size.
double compressed_estimate(const unsigned char* data, size_t count);

}  // namespace segmorph
