#include "json_prepass.h"

#include <cstddef>
#include <cstring>
#include <utility>
#include <vector>

namespace segmorph {
namespace {

// Just enough JSON: objects and arrays as trees, everything else (strings with their quotes and escapes,
// numbers, true/false/null) as the text it was written as, so that writing the tree back changes nothing but
// white space.
struct Json {
  enum class Kind { object, array, scalar } kind = Kind::scalar;
  std::string text;                                   // scalar: as written
  std::vector<std::pair<std::string, Json>> members;  // object: key as written (with quotes), value
  std::vector<Json> items;                            // array

  const Json* member(const char* key) const {
    for (const auto& [name, value] : members)
      if (name == key) return &value;
    return nullptr;
  }
};

constexpr int kMaxDepth = 256;

class Parser {
 public:
  explicit Parser(const std::string& text) : text_(text) {}

  bool parse(Json& out) {
    if (!value(out, 0)) return false;
    skip_space();
    return at_ == text_.size();
  }

 private:
  void skip_space() {
    while (at_ < text_.size() && std::strchr(" \t\r\n", text_[at_]) && text_[at_] != '\0') ++at_;
  }

  bool string(std::string& out) {
    const size_t begin = at_;
    if (at_ >= text_.size() || text_[at_] != '"') return false;
    for (++at_; at_ < text_.size() && text_[at_] != '"'; ++at_)
      if (text_[at_] == '\\') ++at_;  // the escaped character cannot end the string
    if (at_ >= text_.size()) return false;
    ++at_;
    out.assign(text_, begin, at_ - begin);
    return true;
  }

  bool value(Json& out, int depth) {
    if (depth > kMaxDepth) return false;
    skip_space();
    if (at_ >= text_.size()) return false;
    const char c = text_[at_];
    if (c == '{' || c == '[') {
      const bool object = c == '{';
      out.kind = object ? Json::Kind::object : Json::Kind::array;
      ++at_;
      skip_space();
      if (at_ < text_.size() && text_[at_] == (object ? '}' : ']')) return ++at_, true;
      for (;;) {
        if (object) {
          std::string key;
          skip_space();
          if (!string(key)) return false;
          skip_space();
          if (at_ >= text_.size() || text_[at_] != ':') return false;
          ++at_;
          out.members.emplace_back(std::move(key), Json());
          if (!value(out.members.back().second, depth + 1)) return false;
        } else {
          out.items.emplace_back();
          if (!value(out.items.back(), depth + 1)) return false;
        }
        skip_space();
        if (at_ >= text_.size()) return false;
        if (text_[at_] == ',') {
          ++at_;
          continue;
        }
        if (text_[at_] != (object ? '}' : ']')) return false;
        ++at_;
        return true;
      }
    }
    if (c == '"') return string(out.text);
    // A number or a literal: up to the next delimiter (tinygltf checks what it is).
    const size_t begin = at_;
    while (at_ < text_.size() && !std::strchr(",:]}[{\" \t\r\n", text_[at_])) ++at_;
    if (at_ == begin) return false;
    out.text.assign(text_, begin, at_ - begin);
    return true;
  }

  const std::string& text_;
  size_t at_ = 0;
};

void write(const Json& value, std::string& out) {
  switch (value.kind) {
    case Json::Kind::scalar:
      out += value.text;
      break;
    case Json::Kind::object:
      out += '{';
      for (size_t i = 0; i < value.members.size(); ++i) {
        if (i) out += ',';
        out += value.members[i].first;
        out += ':';
        write(value.members[i].second, out);
      }
      out += '}';
      break;
    case Json::Kind::array:
      out += '[';
      for (size_t i = 0; i < value.items.size(); ++i) {
        if (i) out += ',';
        write(value.items[i], out);
      }
      out += ']';
      break;
  }
}

}  // namespace

Status check_json_nesting(const std::string& json, int max_depth) {
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth)
        return Status(StatusCode::bad_data,
                      "cannot parse glTF: JSON nested deeper than " + std::to_string(max_depth) + " levels");
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return Status::Ok();
}

Status drop_draco_indices(std::string& json, bool& changed) {
  changed = false;
  // Most files have no Draco at all: nothing to parse.
  if (json.find("KHR_draco_mesh_compression") == std::string::npos) return Status::Ok();
  Json document;
  if (!Parser(json).parse(document) || document.kind != Json::Kind::object)
    return Status(StatusCode::bad_data, "cannot parse glTF: the JSON is malformed");
  const Json* accessors = document.member("\"accessors\"");
  Json* meshes = nullptr;
  for (auto& [name, value] : document.members)
    if (name == "\"meshes\"") meshes = &value;
  if (!accessors || accessors->kind != Json::Kind::array || !meshes || meshes->kind != Json::Kind::array)
    return Status::Ok();
  for (Json& mesh : meshes->items) {
    for (auto& [mesh_key, primitives] : mesh.members) {
      if (mesh_key != "\"primitives\"" || primitives.kind != Json::Kind::array) continue;
      for (Json& primitive : primitives.items) {
        const Json* extensions = primitive.member("\"extensions\"");
        if (!extensions || !extensions->member("\"KHR_draco_mesh_compression\"")) continue;
        for (size_t i = 0; i < primitive.members.size(); ++i) {
          if (primitive.members[i].first != "\"indices\"") continue;
          // Only an accessor index that names an accessor without a bufferView; anything else is tinygltf's
          // to judge.
          const std::string& text = primitive.members[i].second.text;
          if (text.empty() || text.size() > 9 || text.find_first_not_of("0123456789") != std::string::npos) continue;
          const size_t index = size_t(std::stoul(text));
          if (index >= accessors->items.size() || accessors->items[index].member("\"bufferView\"")) continue;
          primitive.members.erase(primitive.members.begin() + std::ptrdiff_t(i));
          changed = true;
          break;
        }
      }
    }
  }
  if (changed) {
    std::string rewritten;
    rewritten.reserve(json.size());
    write(document, rewritten);
    json = std::move(rewritten);
  }
  return Status::Ok();
}

Status refuse_unreadable_extensions(const std::string& json) {
  static const char* const kUnreadable[] = {"EXT_meshopt_compression", "KHR_meshopt_compression"};
  if (json.find("meshopt_compression") == std::string::npos) return Status::Ok();
  Json document;
  if (!Parser(json).parse(document) || document.kind != Json::Kind::object)
    return Status(StatusCode::bad_data, "cannot parse glTF: the JSON is malformed");
  const Json* used = document.member("\"extensionsUsed\"");
  if (!used || used->kind != Json::Kind::array) return Status::Ok();
  for (const Json& item : used->items)
    for (const char* name : kUnreadable)
      if (item.text == "\"" + std::string(name) + "\"")
        return Status(StatusCode::unsupported, std::string("uses ") + name +
                                                   ", which segmorph does not read: undo it first, for example with "
                                                   "glTF-Transform's 'gltf-transform copy IN OUT.glb'");
  return Status::Ok();
}

}  // namespace segmorph
