// What the codec-level bench tools encode: the first animated node of a glTF file (needs segmorph_pipeline).
#pragma once

#include "gltf/load.h"
#include "sampling/sample.h"

namespace segmorph::bench {

// The first animated node of the glTF file at `path`, sampled as `segmorph bake` samples it.
inline Status sample_first_animated(const char* path, SampledNode& node) {
  tinygltf::Model model;
  Scene scene;
  Status status = load_gltf(path, model);
  if (status.ok()) status = analyze_scene(model, scene);
  if (status.ok() && scene.animated.empty()) status = Status(StatusCode::invalid_argument, "nothing is animated");
  if (status.ok()) status = sample_node(model, scene, scene.animated[0], SampleSettings(), node);
  return status;
}

}  // namespace segmorph::bench
