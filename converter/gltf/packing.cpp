#include "gltf/packing.h"

#include <algorithm>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <unordered_map>

#include "accessor.h"
#include "file_names.h"
#include "segmorph_extension.h"

namespace segmorph {
namespace {

// The MIME type of an image given by URI (a data: URI's own, else by its suffix), for the bufferView it moves into.
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

}  // namespace segmorph
