// engine_decode IN.glb OUT.bin: what an engine does with a file written by `segmorph encode`. It loads the .glb with
// its own glTF loader (tinygltf) and decodes the base meshes with its own Draco, then turns every compressed
// primitive's SEGMORPH_animation_compression stream into frames with segmorph's runtime decoder, through the C API
// only (segmorph/decoder_c.h). It writes every frame as raw little-endian float32 to OUT.bin (primitive by primitive
// in mesh order, clip by clip, frame by frame, vertex by vertex, x y z; for a primitive that keeps its morph targets,
// one clip of the targets' POSITION displacements) and prints one JSON line per clip. docs/runtime.md walks through
// it.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <draco/compression/decode.h>
#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <segmorph/decoder_c.h>

namespace {

const char* const kDraco = "KHR_draco_mesh_compression";
const char* const kSegmorph = "SEGMORPH_animation_compression";

struct Failure {
  std::string message;
};

uint32_t read_u32(const std::string& bytes, size_t at) {
  uint32_t value = 0;
  for (int i = 3; i >= 0; --i) value = value << 8 | uint8_t(bytes[at + size_t(i)]);
  return value;
}

void write_u32(std::string& bytes, uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes.push_back(char(value >> (8 * i)));
}

// tinygltf 2.7 refuses a primitive's `indices` accessor without a bufferView, which KHR_draco_mesh_compression allows
// (the triangles are in the Draco data, and segmorph writes them so). The .glb is given to tinygltf with those
// `indices` removed from its JSON chunk: the triangles come from Draco below.
std::string without_draco_indices(const std::string& glb) {
  if (glb.size() < 20 || glb.compare(0, 4, "glTF") != 0 || read_u32(glb, 4) != 2)
    throw Failure{"not a glTF 2.0 binary (.glb) file"};
  const size_t json_length = read_u32(glb, 12);
  if (read_u32(glb, 16) != 0x4E4F534Au || 20 + json_length > glb.size())
    throw Failure{"the .glb's first chunk is not its JSON"};
  nlohmann::json json = nlohmann::json::parse(glb.substr(20, json_length), nullptr, false);
  if (json.is_discarded()) throw Failure{"the .glb's JSON does not parse"};
  if (json.contains("meshes"))
    for (auto& mesh : json["meshes"])
      if (mesh.contains("primitives"))
        for (auto& primitive : mesh["primitives"])
          if (primitive.contains("extensions") && primitive["extensions"].contains(kDraco)) primitive.erase("indices");
  std::string text = json.dump();
  text.append((4 - text.size() % 4) % 4, ' ');
  std::string rest = glb.substr(20 + json_length);
  std::string out = "glTF";
  write_u32(out, 2);
  write_u32(out, uint32_t(12 + 8 + text.size() + rest.size()));
  write_u32(out, uint32_t(text.size()));
  write_u32(out, 0x4E4F534Au);
  return out + text + rest;
}

// The bytes of bufferView `index`.
std::vector<uint8_t> view_bytes(const tinygltf::Model& model, int index) {
  if (index < 0 || size_t(index) >= model.bufferViews.size()) throw Failure{"a bufferView that does not exist"};
  const tinygltf::BufferView& view = model.bufferViews[size_t(index)];
  if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size() ||
      view.byteOffset + view.byteLength > model.buffers[size_t(view.buffer)].data.size())
    throw Failure{"bufferView " + std::to_string(index) + " is outside its buffer"};
  const unsigned char* data = model.buffers[size_t(view.buffer)].data.data() + view.byteOffset;
  return std::vector<uint8_t>(data, data + view.byteLength);
}

// The base mesh as the decoder needs it: positions (V x 3) and triangles, in Draco's point order.
struct BaseMesh {
  std::vector<float> positions;
  std::vector<uint32_t> indices;
};

BaseMesh draco_base_mesh(const tinygltf::Model& model, const tinygltf::Value& draco_extension) {
  const std::vector<uint8_t> bytes = view_bytes(model, draco_extension.Get("bufferView").GetNumberAsInt());
  const tinygltf::Value& attributes = draco_extension.Get("attributes");
  if (!attributes.Has("POSITION")) throw Failure{"the Draco data has no POSITION"};
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok()) throw Failure{"Draco: " + decoded.status().error_msg_string()};
  const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
  const draco::PointAttribute* position =
      mesh->GetAttributeByUniqueId(uint32_t(attributes.Get("POSITION").GetNumberAsInt()));
  if (!position || position->num_components() != 3) throw Failure{"the Draco data has no 3-component POSITION"};
  BaseMesh base;
  base.positions.resize(size_t(mesh->num_points()) * 3);
  for (uint32_t point = 0; point < mesh->num_points(); ++point)
    if (!position->ConvertValue<float, 3>(position->mapped_index(draco::PointIndex(point)), &base.positions[point * 3]))
      throw Failure{"the Draco POSITION cannot be read as floats"};
  for (uint32_t face = 0; face < mesh->num_faces(); ++face)
    for (int corner = 0; corner < 3; ++corner) base.indices.push_back(mesh->face(draco::FaceIndex(face))[corner].value());
  return base;
}

// A primitive without Draco: its POSITION accessor (float VEC3, tightly packed or strided) and its indices.
BaseMesh plain_base_mesh(const tinygltf::Model& model, const tinygltf::Primitive& primitive) {
  auto read = [&](int index, bool positions) {
    if (index < 0 || size_t(index) >= model.accessors.size()) throw Failure{"an accessor that does not exist"};
    const tinygltf::Accessor& accessor = model.accessors[size_t(index)];
    const std::vector<uint8_t> bytes = view_bytes(model, accessor.bufferView);
    const int size = tinygltf::GetComponentSizeInBytes(uint32_t(accessor.componentType));
    const int components = positions ? 3 : 1;
    if ((positions && (accessor.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || accessor.type != TINYGLTF_TYPE_VEC3)) ||
        size <= 0)
      throw Failure{"POSITION must be float VEC3"};
    const size_t stride = model.bufferViews[size_t(accessor.bufferView)].byteStride
                              ? model.bufferViews[size_t(accessor.bufferView)].byteStride
                              : size_t(size * components);
    if (accessor.count > 0 && accessor.byteOffset + (accessor.count - 1) * stride + size_t(size * components) > bytes.size())
      throw Failure{"an accessor is outside its bufferView"};
    std::vector<double> values;
    for (size_t i = 0; i < accessor.count; ++i)
      for (int c = 0; c < components; ++c) {
        const uint8_t* at = &bytes[accessor.byteOffset + i * stride + size_t(c * size)];
        if (accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) {
          float x;
          std::memcpy(&x, at, 4);
          values.push_back(x);
        } else {
          uint32_t x = 0;
          std::memcpy(&x, at, size_t(size));  // little-endian unsigned index of 1, 2 or 4 bytes
          values.push_back(x);
        }
      }
    return values;
  };
  BaseMesh base;
  for (double x : read(primitive.attributes.at("POSITION"), true)) base.positions.push_back(float(x));
  for (double i : read(primitive.indices, false)) base.indices.push_back(uint32_t(i));
  return base;
}

// Throws with the decoder's message unless `status` is ok.
void check(segmorph_decoder* decoder, segmorph_status status, const std::string& what) {
  if (status != SEGMORPH_STATUS_OK)
    throw Failure{what + ": " + segmorph_status_name(status) + ": " + segmorph_decoder_message(decoder)};
}

int run(const char* in_path, const char* out_path) {
  std::ifstream in(in_path, std::ios::binary);
  if (!in) throw Failure{"cannot read it"};
  const std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string loadable = without_draco_indices(glb);
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string error, warning;
  if (!loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(loadable.data()),
                                   unsigned(loadable.size())))
    throw Failure{"tinygltf: " + error};

  std::FILE* out = std::fopen(out_path, "wb");
  if (!out) throw Failure{std::string("cannot write ") + out_path};
  segmorph_decoder* decoder = segmorph_decoder_create();
  std::vector<float> frames;
  auto write = [&](const std::vector<float>& values) {
    // The floats as they are in memory: little-endian on every machine this example targets.
    if (std::fwrite(values.data(), sizeof(float), values.size(), out) != values.size())
      throw Failure{std::string("cannot write ") + out_path};
  };
  try {
    for (size_t m = 0; m < model.meshes.size(); ++m)
      for (size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
        const tinygltf::Primitive& primitive = model.meshes[m].primitives[p];
        const auto extension = primitive.extensions.find(kSegmorph);
        if (extension == primitive.extensions.end()) continue;
        const std::string what = "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
        const auto draco = primitive.extensions.find(kDraco);
        const BaseMesh base = draco != primitive.extensions.end() ? draco_base_mesh(model, draco->second)
                                                                  : plain_base_mesh(model, primitive);
        const std::vector<uint8_t> stream = view_bytes(model, extension->second.Get("bufferView").GetNumberAsInt());
        const size_t vertices = base.positions.size() / 3;
        check(decoder,
              segmorph_decoder_open(decoder, stream.data(), stream.size(), base.positions.data(), vertices,
                                    base.indices.data(), base.indices.size()),
              what);
        if (extension->second.Has("morphTargets")) {
          // Kept morph targets: their displacements, what the engine's morph target buffers hold.
          frames.resize(segmorph_decode_clip_bound(decoder, 0));
          check(decoder, segmorph_decode_targets(decoder, frames.data(), frames.size()), what);
          write(frames);
          std::printf("{\"mesh\":%zu,\"primitive\":%zu,\"clip\":0,\"targets\":true,\"vertices\":%zu,\"frames\":%zu}\n",
                      m, p, vertices, segmorph_decoder_frame_count(decoder, 0));
          continue;
        }
        const tinygltf::Value& clips = extension->second.Get("clips");
        if (!clips.IsArray() || clips.ArrayLen() != segmorph_decoder_clip_count(decoder))
          throw Failure{what + ": the stream's clips disagree with the extension's"};
        for (size_t c = 0; c < clips.ArrayLen(); ++c) {
          // The clip's times accessor says how many frames to expect: the file's bytes back it.
          const int times = clips.Get(int(c)).Get("times").GetNumberAsInt();
          if (times < 0 || size_t(times) >= model.accessors.size() ||
              model.accessors[size_t(times)].count != segmorph_decoder_frame_count(decoder, c))
            throw Failure{what + ": clip " + std::to_string(c) + "'s times disagree with its frame count"};
          frames.resize(segmorph_decode_clip_bound(decoder, c));
          check(decoder, segmorph_decode_clip(decoder, c, frames.data(), frames.size()), what);
          write(frames);
          std::printf("{\"mesh\":%zu,\"primitive\":%zu,\"clip\":%zu,\"animation\":%d,\"vertices\":%zu,\"frames\":%zu}\n", m,
                      p, c, clips.Get(int(c)).Get("animation").GetNumberAsInt(), vertices,
                      segmorph_decoder_frame_count(decoder, c));
        }
      }
  } catch (...) {
    segmorph_decoder_destroy(decoder);
    std::fclose(out);
    std::remove(out_path);
    throw;
  }
  segmorph_decoder_destroy(decoder);
  if (std::fclose(out) != 0) {
    std::remove(out_path);
    throw Failure{std::string("cannot write ") + out_path};
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: engine_decode IN.glb OUT.bin\n");
    return 2;
  }
  try {
    return run(argv[1], argv[2]);
  } catch (const Failure& failure) {
    std::fprintf(stderr, "engine_decode: %s: %s\n", argv[1], failure.message.c_str());
    return 1;
  }
}
