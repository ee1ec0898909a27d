// The pipeline API's shared pieces (include/segmorph/segmorph.h is the API): the tinygltf model inside a
// segmorph::Model, and a file loaded, decoded, analyzed and sampled, which info, bake, encode and verify start from.
#pragma once

#include <tiny_gltf.h>

#include <exception>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "decoding/decode_file.h"
#include "sampling/sample.h"
#include "segmorph/segmorph.h"
#include "segmorph/status.h"
#include "verify/comparison.h"

namespace segmorph {

// Runs `body` (returning a Status) with exceptions turned into a Status, as the pipeline API promises (errors "never
// as an exception"): a failed allocation (std::bad_alloc, or std::length_error for a size no container can hold) is
// out_of_memory, anything else internal. Every function of segmorph.h runs its work through it.
template <typename Body>
Status guarded(Body&& body) {
  try {
    return body();
  } catch (const std::bad_alloc&) {
    return Status(StatusCode::out_of_memory, "out of memory");
  } catch (const std::length_error&) {
    return Status(StatusCode::out_of_memory, "out of memory: an allocation larger than any container holds");
  } catch (const std::exception& error) {
    return Status(StatusCode::internal, std::string("internal error: ") + error.what());
  }
}

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
