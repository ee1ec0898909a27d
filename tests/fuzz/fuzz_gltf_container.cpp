// libFuzzer target: a whole glTF file (GLB or JSON) through the converter's load path, as the command-line tool
// takes it: load_gltf, then decode_compressed_model (KHR_draco_mesh_compression and SEGMORPH_animation_compression
// back to plain accessors and baked morph targets), then what info, encode and verify do next (analyze_scene,
// sample_node) and what decode does before writing (repack). Seeds: the bundled samples encoded by segmorph
// (tests/fuzz/CMakeLists.txt).
//
// load_gltf reads a path (tinygltf resolves external URIs relative to it), so each input is written to a file in a
// fresh temporary directory, where relative URIs name nothing, and both are removed once it is loaded.
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "decoding/decode_file.h"
#include "gltf/load.h"
#include "gltf/packing.h"
#include "sampling/sample.h"

namespace {

segmorph::Status load_input(const uint8_t* data, size_t size, tinygltf::Model& model) {
  static const char* const tmp = std::getenv("TMPDIR");
  std::string directory = std::string(tmp && *tmp ? tmp : "/tmp") + "/segmorph-fuzz-XXXXXX";
  if (!mkdtemp(directory.data())) std::abort();
  const std::string path = directory + "/input.glb";
  {
    std::ofstream file(path, std::ios::binary);
    file.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    if (!file.flush()) std::abort();
  }
  const segmorph::Status status = segmorph::load_gltf(path, model);
  unlink(path.c_str());
  rmdir(directory.c_str());
  return status;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace segmorph;
  tinygltf::Model model;
  if (!load_input(data, size, model).ok()) return 0;
  if (!decode_compressed_model(model).ok()) return 0;
  Scene scene;
  if (analyze_scene(model, scene).ok())
    for (const AnimatedNode& node : scene.animated) {
      SampledNode sampled;
      if (!sample_node(model, scene, node, SampleSettings(), sampled).ok()) break;
    }
  repack(model);
  return 0;
}
