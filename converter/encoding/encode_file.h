// The whole-file encode behind segmorph::encode (include/segmorph/segmorph.h).
#pragma once

#include <tiny_gltf.h>

#include "pipeline.h"
#include "segmorph/segmorph.h"
#include "segmorph/status.h"

namespace segmorph {

// Encodes the sampled `file` (analyze_model's, sampled with settings.sampling) into `output` as `settings` say. The
// morph targets of the meshes it bakes are released from `file` (their frames are sampled): see release_target_data.
Status encode_sampled(SampledFile& file, const EncodeSettings& settings, tinygltf::Model& output,
                      EncodeReport& report, const Progress& progress);

}  // namespace segmorph
