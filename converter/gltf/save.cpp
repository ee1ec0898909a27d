#include "gltf/save.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "file_names.h"
#include "gltf/glb.h"
#include "gltf/json_reserve.h"
#include "gltf/output_file.h"
#include "gltf/packing.h"
#include "segmorph/version.h"

namespace segmorph {
namespace {

// Images are written from bufferViews, so tinygltf never has to write an image file of its own.
bool write_no_image(const std::string*, const std::string*, const tinygltf::Image*, bool, std::string*, void*) {
  return false;
}

// A double that holds a float exactly (as the numbers of most glTF files do: they were floats in the exporter)
// becomes the double nearest the shortest decimal that reads back as that float, which the JSON writer prints
// in those few digits: 0.9999998807907104 becomes 0.99999988. Readers that take the number as a float get the
// same float; those that keep doubles get it within half a float's last digit, as the exporter meant it. So does
// a float an exporter printed in 15 significant digits (three.js: -0.707106828689575 for the float
// -0.70710682868957519...): the double agrees with the float to those 15 digits. Any other double (a
// georeferenced translation, say) is left as it is.
void shorten(double& value) {
  const float single = float(value);
  if (!std::isfinite(single)) return;
  if (double(single) != value) {
    char as_double[32], as_float[32];
    std::snprintf(as_double, sizeof(as_double), "%.15g", value);
    std::snprintf(as_float, sizeof(as_float), "%.15g", double(single));
    if (std::strcmp(as_double, as_float) != 0) return;
  }
  char text[32];
  const std::to_chars_result end = std::to_chars(text, text + sizeof(text), single);
  if (end.ec != std::errc()) return;
  double shortened = 0;  // read back as a double, independently of the C locale
  if (std::from_chars(text, end.ptr, shortened).ec != std::errc()) return;
  if (float(shortened) == single) value = shortened;
}

void shorten(std::vector<double>& values) {
  for (double& value : values) shorten(value);
}

// The glTF numbers the format defines as floats: node transforms and weights, floating-point accessors' bounds,
// mesh weights, material factors. Extensions and extras are left as they are.
void shorten_float_numbers(tinygltf::Model& model) {
  for (tinygltf::Node& node : model.nodes) {
    shorten(node.translation), shorten(node.rotation), shorten(node.scale), shorten(node.matrix);
    shorten(node.weights);
  }
  for (tinygltf::Accessor& accessor : model.accessors)
    if (accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
      shorten(accessor.minValues), shorten(accessor.maxValues);
  for (tinygltf::Mesh& mesh : model.meshes) shorten(mesh.weights);
  for (tinygltf::Material& material : model.materials) {
    shorten(material.pbrMetallicRoughness.baseColorFactor);
    shorten(material.pbrMetallicRoughness.metallicFactor);
    shorten(material.pbrMetallicRoughness.roughnessFactor);
    shorten(material.emissiveFactor);
    shorten(material.alphaCutoff);
    shorten(material.normalTexture.scale);
    shorten(material.occlusionTexture.strength);
  }
}

// tinygltf writes an object with no properties as null, which is invalid glTF; an empty node or scene (valid, and
// left behind when a skinned node's mesh moves to its baked node) gets its index as a name.
void name_empty_objects(tinygltf::Model& model) {
  for (size_t n = 0; n < model.nodes.size(); ++n) {
    tinygltf::Node& node = model.nodes[n];
    if (node.name.empty() && node.mesh < 0 && node.skin < 0 && node.camera < 0 && node.children.empty() &&
        node.matrix.empty() && node.translation.empty() && node.rotation.empty() && node.scale.empty() &&
        node.weights.empty() && node.extensions.empty() && node.extras.Type() == tinygltf::NULL_TYPE)
      node.name = "node " + std::to_string(n);
  }
  for (size_t s = 0; s < model.scenes.size(); ++s) {
    tinygltf::Scene& scene = model.scenes[s];
    if (scene.name.empty() && scene.nodes.empty() && scene.extensions.empty() &&
        scene.extras.Type() == tinygltf::NULL_TYPE)
      scene.name = "scene " + std::to_string(s);
  }
}

// The JSON of the model to write: `model` with its views at their `packed` places and one buffer of their size, as
// tinygltf writes it: for a .glb compact, with the buffer's byteLength only; for a .gltf (`bin_name` not empty) with
// sorted keys, two spaces and a final newline, and the buffer the file `bin_name` beside it. The buffers' bytes stay
// where they are: they are written from there, after the JSON.
std::string packed_json_of(tinygltf::Model& model, const std::vector<tinygltf::BufferView>& packed,
                           tinygltf::TinyGLTF& writer, const std::string& bin_name) {
  const size_t size = packed_size(packed);
  std::vector<tinygltf::Buffer> buffers;
  buffers.swap(model.buffers);
  std::vector<tinygltf::BufferView> sources = packed;
  sources.swap(model.bufferViews);
  if (size > 0) model.buffers.resize(1);
  std::ostringstream text;
  writer.WriteGltfSceneToStream(&model, text, !bin_name.empty(), bin_name.empty());
  model.buffers.swap(buffers);
  model.bufferViews.swap(sources);
  if (bin_name.empty()) {
    // tinygltf wrote a .glb of an empty buffer: its JSON chunk, the buffer's byteLength set.
    const std::string glb = text.str();
    uint32_t length = 0;
    std::memcpy(&length, glb.data() + 12, 4);
    std::string json = glb.substr(20, length);
    json.erase(json.find_last_not_of(' ') + 1);
    if (size > 0) {
      const std::string empty = "\"buffers\":[{\"byteLength\":0}]";
      const size_t at = json.find(empty);
      if (at == std::string::npos || json.find(empty, at + 1) != std::string::npos) return std::string();
      json.replace(at, empty.size(), "\"buffers\":[{\"byteLength\":" + std::to_string(size) + "}]");
    }
    return json;
  }
  if (size == 0) return text.str();
  nlohmann::json json = nlohmann::json::parse(text.str());
  json["buffers"][0]["byteLength"] = size;
  json["buffers"][0]["uri"] = bin_name;
  return json.dump(2) + "\n";
}

// packed_json_of with memory standing by for the JSON library's destructors (json_reserve.h).
std::string packed_json(tinygltf::Model& model, const std::vector<tinygltf::BufferView>& packed,
                        tinygltf::TinyGLTF& writer, const std::string& bin_name) {
  std::string json;
  {
    const JsonReserve reserve;
    json = packed_json_of(model, packed, writer, bin_name);
    reserve.check();
  }
  return json;
}

}  // namespace

std::string glb_bytes(tinygltf::Model& model) {
  repack(model);
  shorten_float_numbers(model);
  name_empty_objects(model);  // as save_gltf does: the size is the file's
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(write_no_image, nullptr);
  std::ostringstream stream;
  bool written;
  {
    const JsonReserve reserve;
    written = writer.WriteGltfSceneToStream(&model, stream, false, true);
    reserve.check();
  }
  return written ? stream.str() : std::string();
}

size_t glb_size(tinygltf::Model model) {
  return glb_bytes(model).size();
}

void name_generator(tinygltf::Model& model) {
  const std::string ours = "segmorph " + std::to_string(SEGMORPH_VERSION_MAJOR) + "." +
                           std::to_string(SEGMORPH_VERSION_MINOR) + "." + std::to_string(SEGMORPH_VERSION_PATCH);
  std::string& generator = model.asset.generator;
  if (!generator.empty() && generator.rfind("segmorph ", 0) != 0) {
    tinygltf::Value::Object extras, segmorph;
    if (model.asset.extras.IsObject()) extras = model.asset.extras.Get<tinygltf::Value::Object>();
    if (extras.count("segmorph") && extras["segmorph"].IsObject())
      segmorph = extras["segmorph"].Get<tinygltf::Value::Object>();
    segmorph["input_generator"] = tinygltf::Value(generator);
    extras["segmorph"] = tinygltf::Value(std::move(segmorph));
    model.asset.extras = tinygltf::Value(std::move(extras));
  }
  generator = ours;
}

Status save_gltf(tinygltf::Model& model, const std::string& path) {
  const bool binary = has_suffix(path, ".glb") || path == "-";  // the standard output takes a .glb
  if (!binary && !has_suffix(path, ".gltf"))
    return Status(StatusCode::invalid_argument, "output must end in .glb or .gltf");
  const std::vector<tinygltf::BufferView> packed = prune(model);
  shorten_float_numbers(model);
  name_empty_objects(model);
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(write_no_image, nullptr);
  const size_t size = packed_size(packed);
  auto write_bin = [&](std::ostream& out) {
    for_each_packed_byte_run(model, packed, [&](const unsigned char* bytes, size_t count) {
      out.write(reinterpret_cast<const char*>(bytes), std::streamsize(count));
    });
  };

  OutputFile file, bin;
  SEGMORPH_RETURN_IF_ERROR(file.open(path));
  if (binary) {
    // The .glb container (header, JSON chunk padded with spaces, BIN chunk), its BIN written view by view.
    std::string json = packed_json(model, packed, writer, "");
    if (json.empty()) return Status(StatusCode::internal, "the glTF writer's JSON has no buffer to size");
    json.append((4 - json.size() % 4) % 4, ' ');
    if (json.size() + size + 28 > UINT32_MAX)
      return Status(StatusCode::unsupported, "larger than 4 GiB, which a .glb cannot hold");
    std::ostream& out = file.stream();
    out.write("glTF", 4);
    write_le32(out, 2);
    write_le32(out, uint32_t(12 + 8 + json.size() + (size > 0 ? 8 + size : 0)));
    write_le32(out, uint32_t(json.size()));
    write_le32(out, kGlbJsonChunk);
    out << json;
    if (size > 0) {
      write_le32(out, uint32_t(size));
      write_le32(out, kGlbBinChunk);
      write_bin(out);
    }
    SEGMORPH_RETURN_IF_ERROR(file.finish());
    return file.commit();
  }
  // .gltf: the JSON and <stem>.bin beside it, both written whole before either is renamed into place.
  const size_t slash = path.find_last_of('/');
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::string bin_name = name.substr(0, name.find_last_of('.')) + ".bin";
  file.stream() << packed_json(model, packed, writer, bin_name);
  SEGMORPH_RETURN_IF_ERROR(file.finish());
  if (size == 0) return file.commit();
  SEGMORPH_RETURN_IF_ERROR(bin.open(path.substr(0, path.size() - name.size()) + bin_name));
  write_bin(bin.stream());
  SEGMORPH_RETURN_IF_ERROR(bin.finish());
  return OutputFile::commit(bin, file);
}

}  // namespace segmorph
