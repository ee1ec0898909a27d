// The pipeline API's shared pieces (include/segmorph/segmorph.h is the API): the tinygltf model inside a
// segmorph::Model, and a file loaded, decoded, analyzed and sampled, which info, bake, encode and verify start from.
#pragma once

#include <tiny_gltf.h>

#include <vector>

#include "comparison.h"
#include "compressed.h"
#include "sample.h"
#include "segmorph/segmorph.h"
#include "segmorph/status.h"

namespace segmorph {

struct Model::Data {
  tinygltf::Model gltf;
};

// A model decoded (when encoded), analyzed and sampled. Not copyable: sampled nodes point into scene.
struct SampledFile {
  tinygltf::Model model;
  Scene scene;
  std::vector<SampledNode> sampled;  // one per scene.animated, empty when only analyzed
  DecodedSizes decoded;              // what an encoded model held
  SampledFile() = default;
  SampledFile(const SampledFile&) = delete;
  SampledFile& operator=(const SampledFile&) = delete;
};

// `file` from `model` (moved in, or a copy): decoded, its animated nodes found, and, when `sample` is true, sampled.
Status analyze_model(tinygltf::Model&& model, const SampleSettings& settings, bool sample, const Progress& progress,
                     SampledFile& file);
Status analyze_model(const tinygltf::Model& model, const SampleSettings& settings, bool sample,
                     const Progress& progress, SampledFile& file);

// A primitive's errors as the API reports them, from a comparison of the file `model` with another.
PrimitiveError primitive_error(const tinygltf::Model& model, const PrimitiveComparison& compared);

// Calls `progress` when there is one.
inline void report_progress(const Progress& progress, const std::string& message) {
  if (progress) progress(message);
}

}  // namespace segmorph
