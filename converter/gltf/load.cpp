#include "gltf/load.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>

#include "accessor.h"
#include "file_names.h"
#include "gltf/glb.h"
#include "gltf/json_reserve.h"
#include "json_prepass.h"

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
  if (bytes.size() < 20 || read_u32(data + 16) != kGlbJsonChunk) return Status::Ok();
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
  bool loaded, short_of_memory;
  {
    const JsonReserve reserve;  // for the JSON library's destructors (json_reserve.h)
    loaded = binary ? loader.LoadBinaryFromMemory(&model, &error, &warning,
                                                  reinterpret_cast<const unsigned char*>(bytes.data()),
                                                  unsigned(bytes.size()), directory)
                    : loader.LoadASCIIFromString(&model, &error, &warning, bytes.data(), unsigned(bytes.size()),
                                                 directory);
    short_of_memory = reserve.used();
  }
  // tinygltf catches a failed allocation of its JSON parser and says so in its message.
  if (short_of_memory || (!loaded && error.find("bad_alloc") != std::string::npos))
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

}  // namespace segmorph
