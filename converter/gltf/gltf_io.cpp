#include "gltf/gltf_io.h"

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <unordered_map>

#include "accessor.h"
#include "file_names.h"
#include "gltf/output_file.h"
#include "json_prepass.h"
#include "segmorph/version.h"
#include "segmorph_extension.h"

namespace segmorph {
namespace {

// tinygltf's messages may span lines; errors are reported on one.
std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  std::string out;
  for (char c : s) {
    if (c == '\n')
      out += "; ";
    else if (c != '\r')
      out += c;
  }
  return out;
}

// Keeps an image's encoded bytes as they are (tinygltf would decode them to pixels and re-encode on save).
bool keep_encoded_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                        const unsigned char* bytes, int size, void*) {
  image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

// Images are written from bufferViews, so tinygltf never has to write an image file of its own.
bool write_no_image(const std::string*, const std::string*, const tinygltf::Image*, bool, std::string*, void*) {
  return false;
}

// Extensions that store geometry in a form this reader does not decode.
std::string mime_of_uri(const std::string& uri) {
  if (uri.rfind("data:", 0) == 0) {
    const size_t end = uri.find_first_of(";,");
    return end == std::string::npos ? "" : uri.substr(5, end - 5);
  }
  if (has_suffix(uri, ".png")) return "image/png";
  if (has_suffix(uri, ".jpg") || has_suffix(uri, ".jpeg")) return "image/jpeg";
  if (has_suffix(uri, ".webp")) return "image/webp";
  if (has_suffix(uri, ".ktx2")) return "image/ktx2";
  return "";
}

// Index remapping for one kind of object: old index -> new index, or -1 when dropped.
struct Remap {
  std::vector<int> to_new;
  std::vector<int> kept;  // old indices in new order

  explicit Remap(size_t n) : to_new(n, -1) {}
  void keep(int old) {
    if (old >= 0 && size_t(old) < to_new.size() && to_new[size_t(old)] < 0) {
      to_new[size_t(old)] = 0;  // marked; numbered in finish()
    }
  }
  void finish() {
    for (size_t i = 0; i < to_new.size(); ++i)
      if (to_new[i] >= 0) {
        to_new[i] = int(kept.size());
        kept.push_back(int(i));
      }
  }
  int operator()(int old) const { return old >= 0 && size_t(old) < to_new.size() ? to_new[size_t(old)] : -1; }
};

template <typename T>
std::vector<T> select(const std::vector<T>& items, const Remap& remap) {
  std::vector<T> out;
  out.reserve(remap.kept.size());
  for (int old : remap.kept) out.push_back(items[size_t(old)]);
  return out;
}

const char* const kInstancing = "EXT_mesh_gpu_instancing";

// Calls f(accessor index&) for every accessor reference in the model.
template <typename F>
void for_each_accessor_ref(tinygltf::Model& model, F f) {
  for (tinygltf::Mesh& mesh : model.meshes)
    for (tinygltf::Primitive& primitive : mesh.primitives) {
      for (auto& attribute : primitive.attributes) f(attribute.second);
      if (primitive.indices >= 0) f(primitive.indices);
      for (auto& target : primitive.targets)
        for (auto& attribute : target) f(attribute.second);
    }
  for (tinygltf::Skin& skin : model.skins)
    if (skin.inverseBindMatrices >= 0) f(skin.inverseBindMatrices);
  for (tinygltf::Animation& animation : model.animations)
    for (tinygltf::AnimationSampler& sampler : animation.samplers) {
      f(sampler.input);
      f(sampler.output);
    }
  // The frame times SEGMORPH_animation_compression names.
  for (tinygltf::Mesh& mesh : model.meshes)
    for (tinygltf::Primitive& primitive : mesh.primitives) {
      auto it = primitive.extensions.find(kExtensionName);
      CompressedPrimitive compressed;
      if (it == primitive.extensions.end() || !parse_compressed_primitive(it->second, compressed).ok()) continue;
      for (CompressedClip& clip : compressed.clips) f(clip.times);
      it->second = compressed_primitive_value(compressed);
    }
  for (tinygltf::Node& node : model.nodes) {
    auto it = node.extensions.find(kInstancing);
    if (it == node.extensions.end() || !it->second.IsObject() || !it->second.Has("attributes")) continue;
    tinygltf::Value::Object extension = it->second.Get<tinygltf::Value::Object>();
    if (!extension["attributes"].IsObject()) continue;
    tinygltf::Value::Object attributes = extension["attributes"].Get<tinygltf::Value::Object>();
    for (auto& attribute : attributes) {
      if (!attribute.second.IsNumber()) continue;
      int index = attribute.second.GetNumberAsInt();
      f(index);
      attribute.second = tinygltf::Value(index);
    }
    extension["attributes"] = tinygltf::Value(std::move(attributes));
    it->second = tinygltf::Value(std::move(extension));
  }
}

// Calls f(bufferView index&) for the bufferViews that KHR_draco_mesh_compression and
// SEGMORPH_animation_compression name on primitives, and SEGMORPH_animation_compression on animations.
template <typename F>
void for_each_extension_view(tinygltf::Model& model, F f) {
  for (tinygltf::Mesh& mesh : model.meshes)
    for (tinygltf::Primitive& primitive : mesh.primitives) {
      auto compressed_it = primitive.extensions.find(kExtensionName);
      CompressedPrimitive compressed;
      if (compressed_it != primitive.extensions.end() &&
          parse_compressed_primitive(compressed_it->second, compressed).ok()) {
        f(compressed.buffer_view);
        compressed_it->second = compressed_primitive_value(compressed);
      }
      auto draco_it = primitive.extensions.find(kDracoExtensionName);
      DracoPrimitive draco;
      if (draco_it != primitive.extensions.end() && parse_draco_primitive(draco_it->second, draco).ok()) {
        f(draco.buffer_view);
        draco_it->second = draco_primitive_value(draco);
      }
    }
  for (tinygltf::Animation& animation : model.animations) {
    auto it = animation.extensions.find(kExtensionName);
    CompressedAnimation coded;
    if (it != animation.extensions.end() && parse_compressed_animation(it->second, coded).ok()) {
      f(coded.buffer_view);
      it->second = compressed_animation_value(coded);
    }
  }
}

uint32_t read_u32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
void put_u32(std::string& out, size_t at, uint32_t value) {
  for (int i = 0; i < 4; ++i) out[at + size_t(i)] = char(value >> (8 * i));
}

// A whole file's bytes made safe and acceptable for tinygltf 2.7: the JSON checked by check_json_nesting and
// passed through drop_draco_indices (rewritten in place when that changes it); a GLB's chunk lengths checked
// against its size. A GLB without a JSON chunk first is left for tinygltf to report.
Status prepare_for_tinygltf(bool binary, std::string& bytes) {
  bool changed = false;
  if (!binary) {
    SEGMORPH_RETURN_IF_ERROR(check_json_nesting(bytes));
    SEGMORPH_RETURN_IF_ERROR(refuse_unreadable_extensions(bytes));
    return drop_draco_indices(bytes, changed);
  }
  // GLB: a 12-byte header, then the JSON chunk (length, type, data), then the rest, kept as it is.
  const auto* data = reinterpret_cast<const unsigned char*>(bytes.data());
  if (bytes.size() < 20 || read_u32(data + 16) != 0x4E4F534Au) return Status::Ok();
  // tinygltf 2.7 does not check a chunk's length against the data it has (found by fuzzing: it reads past the
  // end), so every chunk is checked here, and the header's total length.
  const Status malformed(StatusCode::bad_data, "cannot parse glTF: GLB chunk lengths disagree with the file size");
  if (read_u32(data + 8) != bytes.size()) return malformed;
  for (uint64_t at = 12; at < bytes.size(); at += 8 + uint64_t(read_u32(data + at)))
    if (at + 8 > bytes.size() || at + 8 + read_u32(data + at) > bytes.size()) return malformed;
  const uint64_t json_length = read_u32(data + 12);
  std::string json = bytes.substr(20, size_t(json_length));
  SEGMORPH_RETURN_IF_ERROR(check_json_nesting(json));
  SEGMORPH_RETURN_IF_ERROR(refuse_unreadable_extensions(json));
  SEGMORPH_RETURN_IF_ERROR(drop_draco_indices(json, changed));
  if (!changed) return Status::Ok();
  while (json.size() % 4) json += ' ';
  std::string rewritten = bytes.substr(0, 20) + json;
  rewritten.append(bytes, size_t(20 + json_length), std::string::npos);
  put_u32(rewritten, 8, uint32_t(rewritten.size()));
  put_u32(rewritten, 12, uint32_t(json.size()));
  bytes = std::move(rewritten);
  return Status::Ok();
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

}  // namespace

bool has_gltf_extension(const std::string& path) {
  return has_suffix(path, ".glb") || has_suffix(path, ".gltf");
}

Status load_gltf(const std::string& path, tinygltf::Model& model, std::vector<std::string>* warnings) {
  // Read once; tinygltf parses from memory (its sizes are 32-bit). "-" is the standard input.
  std::string bytes;
  if (path == "-") {
    std::cin.exceptions(std::ios::goodbit);
    bytes.assign(std::istreambuf_iterator<char>(std::cin), std::istreambuf_iterator<char>());
    if (std::cin.bad()) return Status(StatusCode::io_error, "cannot read the standard input");
  } else {
    std::ifstream file(path, std::ios::binary);
    struct stat info {};
    if (!file || stat(path.c_str(), &info) != 0)
      return Status(StatusCode::io_error, "cannot open: " + std::string(std::strerror(errno)));
    if (S_ISDIR(info.st_mode)) return Status(StatusCode::io_error, "is a directory, not a glTF file");
    // In one read of the size stat gives (a pipe or special file, of no size, is read to its end): a character at
    // a time took 15 s for a 725 MB file, and growing the string held up to twice it.
    if (S_ISREG(info.st_mode) && info.st_size > 0) {
      if (uint64_t(info.st_size) > UINT32_MAX)
        return Status(StatusCode::unsupported, "larger than 4 GiB, which the glTF loader cannot read");
      bytes.resize(size_t(info.st_size));
      file.read(bytes.data(), std::streamsize(bytes.size()));
      if (size_t(file.gcount()) != bytes.size())
        return Status(StatusCode::io_error, "cannot read: " + std::string(std::strerror(errno)));
    } else {
      bytes.assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
    }
  }
  if (bytes.size() > UINT32_MAX)
    return Status(StatusCode::unsupported, "larger than 4 GiB, which the glTF loader cannot read");
  const bool binary = bytes.compare(0, 4, "glTF") == 0;
  if (!binary) {
    // A JSON glTF starts with '{' after optional white space and byte-order mark.
    const size_t first = bytes.find_first_not_of(" \t\n\r\v\f\xEF\xBB\xBF");
    if (first == std::string::npos || bytes[first] != '{')
      return Status(StatusCode::bad_data, "not a glTF file (neither GLB nor JSON)");
  }

  // Valid files tinygltf 2.7 refuses are rewritten first, and files that would crash it are refused
  // (json_prepass.h, prepare_for_tinygltf).
  SEGMORPH_RETURN_IF_ERROR(prepare_for_tinygltf(binary, bytes));

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_encoded_image, nullptr);
  std::string error, warning;
  const size_t slash = path.find_last_of('/');
  const std::string directory = slash == std::string::npos ? std::string() : path.substr(0, slash);
  const bool loaded =
      binary
          ? loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(bytes.data()),
                                        unsigned(bytes.size()), directory)
          : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(), unsigned(bytes.size()), directory);
  // tinygltf catches a failed allocation of its JSON parser and says so in its message.
  if (!loaded && error.find("bad_alloc") != std::string::npos)
    return Status(StatusCode::out_of_memory, "out of memory while parsing the glTF JSON");
  if (!loaded) return Status(StatusCode::bad_data, "cannot parse glTF: " + one_line(error.empty() ? warning : error));
  if (warnings && !warning.empty()) warnings->push_back(one_line(warning));

  // tinygltf leaves bufferViews unchecked against their buffers. Reads check the views they use, but repack
  // copies every view an accessor names, read or not: all are checked here, once.
  for (size_t view = 0; view < model.bufferViews.size(); ++view) {
    const unsigned char* data = nullptr;
    size_t size = 0;
    SEGMORPH_RETURN_IF_ERROR(buffer_view_bytes(model, int(view), "glTF", &data, &size));
  }
  return Status::Ok();
}

namespace {

// repack's packing without a second buffer, where it can: every kept view (model.bufferViews, where its bytes are)
// in buffer 0, in increasing order without overlap (as the loader and AccessorWriter leave them), and none's packed
// place after its present one: each moves down to its place in order, the gaps zeroed: the bytes the copy writes, with
// no copy of a file-sized buffer. False, with nothing changed, when the views are otherwise.
bool pack_in_place(tinygltf::Model& model, const std::vector<tinygltf::BufferView>& packed) {
  if (model.buffers.empty()) return false;
  std::vector<unsigned char>& data = model.buffers[0].data;
  size_t source_end = 0;
  for (size_t i = 0; i < packed.size(); ++i) {
    const tinygltf::BufferView& view = model.bufferViews[i];
    if (view.buffer != 0 || view.byteOffset < source_end || view.byteOffset < packed[i].byteOffset ||
        view.byteOffset + view.byteLength > data.size())
      return false;
    source_end = view.byteOffset + view.byteLength;
  }
  size_t end = 0;
  for (size_t i = 0; i < packed.size(); ++i) {
    const tinygltf::BufferView& view = model.bufferViews[i];
    std::fill(data.begin() + long(end), data.begin() + long(packed[i].byteOffset), 0);
    if (view.byteLength > 0) std::memmove(data.data() + packed[i].byteOffset, data.data() + view.byteOffset, view.byteLength);
    end = packed[i].byteOffset + view.byteLength;
  }
  data.resize(packed.empty() ? 0 : (end + 3) / 4 * 4);
  std::fill(data.begin() + long(std::min(end, data.size())), data.end(), 0);
  tinygltf::Buffer buffer;
  buffer.data.swap(data);
  model.buffers.clear();
  if (!buffer.data.empty()) model.buffers.push_back(std::move(buffer));
  return true;
}

}  // namespace

namespace {

// Everything repack does but moving bytes: what nothing refers to goes (meshes, skins, samplers, accessors,
// bufferViews), images given by URI move into bufferViews (of buffers of their own), and the kept bufferViews are
// renumbered where they lie. Returns them at their places in the one buffer repack packs.
std::vector<tinygltf::BufferView> prune(tinygltf::Model& model) {
  // Meshes and skins in use.
  Remap meshes(model.meshes.size()), skins(model.skins.size());
  for (const tinygltf::Node& node : model.nodes) {
    meshes.keep(node.mesh);
    skins.keep(node.skin);
  }
  meshes.finish();
  skins.finish();
  for (tinygltf::Node& node : model.nodes) {
    node.mesh = meshes(node.mesh);
    node.skin = skins(node.skin);
  }
  model.meshes = select(model.meshes, meshes);
  model.skins = select(model.skins, skins);

  // Animation samplers in use, per animation (a coded one is: its stream holds it).
  for (tinygltf::Animation& animation : model.animations) {
    Remap samplers(animation.samplers.size());
    for (const tinygltf::AnimationChannel& channel : animation.channels) samplers.keep(channel.sampler);
    auto coded_it = animation.extensions.find(kExtensionName);
    CompressedAnimation coded;
    const bool is_coded = coded_it != animation.extensions.end() && parse_compressed_animation(coded_it->second, coded).ok();
    if (is_coded)
      for (int sampler : coded.samplers) samplers.keep(sampler);
    samplers.finish();
    for (tinygltf::AnimationChannel& channel : animation.channels) channel.sampler = samplers(channel.sampler);
    if (is_coded) {
      for (int& sampler : coded.samplers) sampler = samplers(sampler);
      coded_it->second = compressed_animation_value(coded);
    }
    animation.samplers = select(animation.samplers, samplers);
  }

  // Accessors in use.
  Remap accessors(model.accessors.size());
  for_each_accessor_ref(model, [&](int& index) { accessors.keep(index); });
  accessors.finish();
  for_each_accessor_ref(model, [&](int& index) { index = accessors(index); });
  model.accessors = select(model.accessors, accessors);

  // Images given by URI (data: or a file) move into bufferViews, so the output is self-contained.
  std::vector<tinygltf::BufferView> image_views;  // appended after the kept views
  for (tinygltf::Image& image : model.images) {
    if (image.bufferView < 0 && !image.image.empty()) {
      const std::string mime = image.mimeType.empty() ? mime_of_uri(image.uri) : image.mimeType;
      if (!mime.empty()) {
        image.mimeType = mime;
        image.uri.clear();
        image.bufferView = int(model.bufferViews.size() + image_views.size());
        tinygltf::BufferView view;
        view.buffer = int(model.buffers.size());  // placeholder buffer holding the image bytes
        view.byteLength = image.image.size();
        tinygltf::Buffer bytes;
        bytes.data = image.image;
        model.buffers.push_back(std::move(bytes));
        image_views.push_back(view);
      }
    }
    image.image.clear();
    image.as_is = false;
  }
  model.bufferViews.insert(model.bufferViews.end(), image_views.begin(), image_views.end());

  // BufferViews in use.
  Remap views(model.bufferViews.size());
  for (const tinygltf::Accessor& accessor : model.accessors) {
    views.keep(accessor.bufferView);
    if (accessor.sparse.isSparse) {
      views.keep(accessor.sparse.indices.bufferView);
      views.keep(accessor.sparse.values.bufferView);
    }
  }
  for (const tinygltf::Image& image : model.images) views.keep(image.bufferView);
  for_each_extension_view(model, [&](int& view) { views.keep(view); });
  views.finish();
  for_each_extension_view(model, [&](int& view) { view = views(view); });
  for (tinygltf::Accessor& accessor : model.accessors) {
    accessor.bufferView = views(accessor.bufferView);
    if (accessor.sparse.isSparse) {
      accessor.sparse.indices.bufferView = views(accessor.sparse.indices.bufferView);
      accessor.sparse.values.bufferView = views(accessor.sparse.values.bufferView);
    }
  }
  for (tinygltf::Image& image : model.images) image.bufferView = views(image.bufferView);

  model.bufferViews = select(model.bufferViews, views);
  // Their places in the one buffer: in order, each at a multiple of 4.
  std::vector<tinygltf::BufferView> packed = model.bufferViews;
  size_t end = 0;
  for (tinygltf::BufferView& view : packed) {
    view.buffer = 0;
    view.byteOffset = (end + 3) / 4 * 4;
    end = view.byteOffset + view.byteLength;
  }
  return packed;
}

}  // namespace

void release_target_data(tinygltf::Model& model, const std::vector<bool>& meshes) {
  // The targets' accessors, and how often anything refers to each: a target's is released when nothing else does.
  std::vector<size_t> references(model.accessors.size(), 0), target_references(model.accessors.size(), 0);
  for_each_accessor_ref(model, [&](int& index) {
    if (index >= 0 && size_t(index) < references.size()) ++references[size_t(index)];
  });
  for (size_t m = 0; m < model.meshes.size() && m < meshes.size(); ++m)
    if (meshes[m])
      for (const tinygltf::Primitive& primitive : model.meshes[m].primitives)
        for (const auto& target : primitive.targets)
          for (const auto& attribute : target)
            if (attribute.second >= 0 && size_t(attribute.second) < references.size())
              ++target_references[size_t(attribute.second)];
  bool released = false;
  for (size_t a = 0; a < model.accessors.size(); ++a)
    if (target_references[a] > 0 && target_references[a] == references[a]) {
      tinygltf::Accessor& accessor = model.accessors[a];
      released = released || accessor.bufferView >= 0 || accessor.sparse.isSparse;
      accessor.bufferView = -1;
      accessor.byteOffset = 0;
      accessor.sparse.isSparse = false;
      accessor.sparse.count = 0;
      accessor.sparse.indices.bufferView = accessor.sparse.values.bufferView = -1;
    }
  if (!released) return;

  // Each buffer rebuilt from the views still referred to, in index order, each at a multiple of 4.
  std::vector<bool> used(model.bufferViews.size(), false);
  const auto use = [&](int view) {
    if (view >= 0 && size_t(view) < used.size()) used[size_t(view)] = true;
  };
  for (const tinygltf::Accessor& accessor : model.accessors) {
    use(accessor.bufferView);
    if (accessor.sparse.isSparse) use(accessor.sparse.indices.bufferView), use(accessor.sparse.values.bufferView);
  }
  for (const tinygltf::Image& image : model.images) use(image.bufferView);
  for_each_extension_view(model, [&](int& view) { use(view); });
  for (size_t b = 0; b < model.buffers.size(); ++b) {
    std::vector<unsigned char> kept;
    for (size_t v = 0; v < model.bufferViews.size(); ++v) {
      tinygltf::BufferView& view = model.bufferViews[v];
      if (view.buffer != int(b)) continue;
      if (!used[v]) {  // nothing refers to it: saving drops it
        view.byteOffset = 0, view.byteLength = 0;
        continue;
      }
      const unsigned char* data = nullptr;
      size_t size = 0;
      if (!buffer_view_bytes(model, int(v), "glTF", &data, &size).ok()) continue;  // load_gltf checked every view
      kept.resize((kept.size() + 3) / 4 * 4, 0);
      const size_t offset = kept.size();
      kept.insert(kept.end(), data, data + size);
      view.byteOffset = offset;
    }
    model.buffers[b].data.swap(kept);
  }
}

namespace {

// The packed buffer's bytes (a multiple of 4) for views at their packed places.
size_t packed_size(const std::vector<tinygltf::BufferView>& packed) {
  return packed.empty() ? 0 : (packed.back().byteOffset + packed.back().byteLength + 3) / 4 * 4;
}

// Calls write(bytes, count) with the packed buffer's bytes, in order: each view's bytes from where `model`'s views
// hold them now, zeros before it up to its packed place and at the end.
template <typename Write>
void for_each_packed_byte_run(const tinygltf::Model& model, const std::vector<tinygltf::BufferView>& packed,
                              Write write) {
  static const unsigned char zeros[4] = {0, 0, 0, 0};
  size_t end = 0;
  for (size_t i = 0; i < packed.size(); ++i) {
    const tinygltf::BufferView& source = model.bufferViews[i];
    write(zeros, packed[i].byteOffset - end);
    write(model.buffers[size_t(source.buffer)].data.data() + source.byteOffset, source.byteLength);
    end = packed[i].byteOffset + packed[i].byteLength;
  }
  write(zeros, packed_size(packed) - end);
}

}  // namespace

void repack(tinygltf::Model& model) {
  std::vector<tinygltf::BufferView> packed = prune(model);
  if (pack_in_place(model, packed)) {
    model.bufferViews = std::move(packed);
    return;
  }
  tinygltf::Buffer buffer;
  buffer.data.reserve(packed_size(packed));  // grows once
  for_each_packed_byte_run(model, packed, [&](const unsigned char* bytes, size_t count) {
    buffer.data.insert(buffer.data.end(), bytes, bytes + count);
  });
  model.bufferViews = std::move(packed);
  model.buffers.clear();
  if (!buffer.data.empty()) model.buffers.push_back(std::move(buffer));
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

namespace {
void name_empty_objects(tinygltf::Model& model);
}  // namespace

namespace {

// The .glb save_gltf would write for `model`, which is repacked as save_gltf repacks it (empty if it cannot be
// written).
std::string glb_bytes(tinygltf::Model& model) {
  repack(model);
  shorten_float_numbers(model);
  name_empty_objects(model);  // as save_gltf does: the size is the file's
  tinygltf::TinyGLTF writer;
  writer.SetImageWriter(write_no_image, nullptr);
  std::ostringstream stream;
  return writer.WriteGltfSceneToStream(&model, stream, false, true) ? stream.str() : std::string();
}

}  // namespace

size_t glb_size(tinygltf::Model model) {
  return glb_bytes(model).size();
}

double compressed_estimate(const unsigned char* data, size_t count) {
  if (count == 0) return 0;
  auto entropy_bytes = [](const auto& counts, double total) {
    double bits = 0;
    for (const auto& entry : counts) bits -= double(entry.second) * std::log2(double(entry.second) / total);
    return bits / 8;
  };
  std::map<unsigned char, size_t> bytes;
  for (size_t i = 0; i < count; ++i) ++bytes[data[i]];
  double estimate = std::min(double(count), entropy_bytes(bytes, double(count)));
  if (count >= 64 && count % 4 == 0) {
    std::unordered_map<uint32_t, size_t> words;
    for (size_t i = 0; i < count; i += 4) {
      uint32_t word;
      std::memcpy(&word, data + i, 4);
      ++words[word];
    }
    estimate = std::min(estimate, entropy_bytes(words, double(count / 4)) + 4.0 * double(words.size()));
  }
  return estimate;
}

size_t glb_delivered_estimate(tinygltf::Model model, size_t* size) {
  const std::string glb = glb_bytes(model);
  if (size) *size = glb.size();
  if (glb.empty()) return 0;
  const auto* bytes = reinterpret_cast<const unsigned char*>(glb.data());
  auto u32 = [&](size_t at) { return read_u32(bytes + at); };
  if (glb.size() < 20) return glb.size();
  const size_t json = u32(12);
  double estimate = 20 + compressed_estimate(bytes + 20, std::min(json, glb.size() - 20));
  const size_t bin = 20 + json;
  if (bin + 8 <= glb.size()) {
    const size_t length = std::min<size_t>(u32(bin), glb.size() - bin - 8);
    size_t covered = 0;
    for (const tinygltf::BufferView& view : model.bufferViews)
      if (view.buffer == 0 && view.byteOffset + view.byteLength <= length) {
        estimate += compressed_estimate(bytes + bin + 8 + view.byteOffset, view.byteLength);
        covered += view.byteLength;
      }
    estimate += 8 + double(length - std::min(covered, length));
  }
  return size_t(std::ceil(estimate));
}

namespace {

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
std::string packed_json(tinygltf::Model& model, const std::vector<tinygltf::BufferView>& packed,
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

void write_le32(std::ostream& out, uint32_t value) {
  const unsigned char bytes[4] = {uint8_t(value), uint8_t(value >> 8), uint8_t(value >> 16), uint8_t(value >> 24)};
  out.write(reinterpret_cast<const char*>(bytes), 4);
}

}  // namespace

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
    write_le32(out, 0x4E4F534A);  // JSON
    out << json;
    if (size > 0) {
      write_le32(out, uint32_t(size));
      write_le32(out, 0x004E4942);  // BIN
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
