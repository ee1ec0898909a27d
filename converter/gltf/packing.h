// What a written glTF holds: what nothing refers to dropped, and the data that stays packed into one buffer, in
// place where it can be (save.cpp writes the packed buffer view by view instead of building it).
#pragma once

#include <cstddef>
#include <vector>

#include <tiny_gltf.h>

namespace segmorph {

// Frees the bytes of the morph targets of the meshes `meshes` marks (one entry per mesh): their accessors keep their
// count, type and bounds but lose their data (glTF's all-zero form; an accessor something else also refers to keeps
// it), and each buffer shrinks to the views something still refers to, every index kept (a view nothing refers to
// is left empty, and saving drops it). For meshes whose frames are sampled and that are baked anyway: an encode then
// holds a long sequence of one-hot targets in its frames alone.
void release_target_data(tinygltf::Model& model, const std::vector<bool>& meshes);

// Drops meshes, skins, accessors, bufferViews and animation samplers nothing refers to, and packs all
// remaining data, embedded images included, into one buffer (in place, without a second buffer, when the views
// already lie in order in the first one).
void repack(tinygltf::Model& model);

// Everything repack does but moving bytes: what nothing refers to goes (meshes, skins, samplers, accessors,
// bufferViews), images given by URI move into bufferViews (of buffers of their own), and the kept bufferViews are
// renumbered where they lie. Returns them at their places in the one buffer repack packs.
std::vector<tinygltf::BufferView> prune(tinygltf::Model& model);

// The packed buffer's bytes (a multiple of 4) for views at their packed places.
inline size_t packed_size(const std::vector<tinygltf::BufferView>& packed) {
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

}  // namespace segmorph
