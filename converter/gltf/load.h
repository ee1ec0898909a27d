// Loading whole glTF files (.gltf with its resources, or .glb, or the standard input).
#pragma once

#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "segmorph/status.h"

namespace segmorph {

// Loads `path`. Images are kept as their encoded bytes (never decoded), so they pass through unchanged.
// Refuses what segmorph cannot read correctly: files whose geometry is compressed by an extension it does
// not decode. Non-fatal remarks of the parser go to `warnings`.
Status load_gltf(const std::string& path, tinygltf::Model& model, std::vector<std::string>* warnings = nullptr);

// has_gltf_extension(path) is declared in include/segmorph/segmorph.h.

}  // namespace segmorph
