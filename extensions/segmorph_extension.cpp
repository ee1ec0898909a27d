#include "segmorph_extension.h"

#include <algorithm>

namespace segmorph {
namespace {

Status missing(const std::string& object, const std::string& member) {
  return Status(StatusCode::bad_data, object + ": \"" + member + "\" is missing or not of the right type");
}

bool get_index(const tinygltf::Value& value, const std::string& key, int& out) {
  if (!value.IsObject() || !value.Has(key) || !value.Get(key).IsNumber()) return false;
  const double number = value.Get(key).GetNumberAsDouble();
  if (!(number >= 0) || number > 2147483647.0 || number != double(int(number))) return false;
  out = int(number);
  return true;
}

}  // namespace

Status parse_compressed_primitive(const tinygltf::Value& value, CompressedPrimitive& out) {
  const std::string object = kExtensionName;
  out = CompressedPrimitive();
  if (!get_index(value, "bufferView", out.buffer_view)) return missing(object, "bufferView");
  if (value.Has("morphTargets")) {
    if (!value.Get("morphTargets").IsBool() || !value.Get("morphTargets").Get<bool>())
      return Status(StatusCode::bad_data, object + ": \"morphTargets\" must be true when present");
    if (value.Has("clips")) return Status(StatusCode::bad_data, object + ": \"morphTargets\" and \"clips\" exclude each other");
    out.morph_targets = true;
    return Status::Ok();
  }
  if (!value.Has("clips") || !value.Get("clips").IsArray() || value.Get("clips").ArrayLen() == 0)
    return missing(object, "clips");
  const tinygltf::Value& clips = value.Get("clips");
  for (size_t i = 0; i < clips.ArrayLen(); ++i) {
    const tinygltf::Value& clip = clips.Get(int(i));
    CompressedClip parsed;
    if (!get_index(clip, "animation", parsed.animation)) return missing(object + " clip", "animation");
    if (!get_index(clip, "times", parsed.times)) return missing(object + " clip", "times");
    if (clip.Has("interpolation")) {
      if (!clip.Get("interpolation").IsString()) return missing(object + " clip", "interpolation");
      const std::string interpolation = clip.Get("interpolation").Get<std::string>();
      if (interpolation != "LINEAR" && interpolation != "STEP")
        return Status(StatusCode::bad_data, object + " clip: unknown interpolation " + interpolation);
      parsed.step = interpolation == "STEP";
    }
    out.clips.push_back(parsed);
  }
  return Status::Ok();
}

Status parse_draco_primitive(const tinygltf::Value& value, DracoPrimitive& out) {
  const std::string object = kDracoExtensionName;
  out = DracoPrimitive();
  if (!get_index(value, "bufferView", out.buffer_view)) return missing(object, "bufferView");
  if (!value.Has("attributes") || !value.Get("attributes").IsObject()) return missing(object, "attributes");
  const tinygltf::Value& attributes = value.Get("attributes");
  for (const std::string& key : attributes.Keys()) {
    int id = -1;
    if (!get_index(attributes, key, id)) return missing(object + " attributes", key);
    out.attributes[key] = id;
  }
  return Status::Ok();
}

Status parse_compressed_animation(const tinygltf::Value& value, CompressedAnimation& out) {
  const std::string object = std::string(kExtensionName) + " (animation)";
  out = CompressedAnimation();
  if (!get_index(value, "bufferView", out.buffer_view)) return missing(object, "bufferView");
  if (!value.Has("samplers") || !value.Get("samplers").IsArray() || value.Get("samplers").ArrayLen() == 0)
    return missing(object, "samplers");
  const tinygltf::Value& samplers = value.Get("samplers");
  for (size_t i = 0; i < samplers.ArrayLen(); ++i) {
    const tinygltf::Value& item = samplers.Get(int(i));
    if (!item.IsNumber() || !(item.GetNumberAsDouble() >= 0) || item.GetNumberAsDouble() > 2147483647.0 ||
        item.GetNumberAsDouble() != double(int(item.GetNumberAsDouble())))
      return Status(StatusCode::bad_data, object + ": \"samplers\" must hold sampler indices");
    const int sampler = int(item.GetNumberAsDouble());
    if (std::find(out.samplers.begin(), out.samplers.end(), sampler) != out.samplers.end())
      return Status(StatusCode::bad_data, object + ": sampler " + std::to_string(sampler) + " is listed twice");
    out.samplers.push_back(sampler);
  }
  return Status::Ok();
}

bool is_placeholder_channel(const tinygltf::AnimationChannel& channel) {
  const auto it = channel.extensions.find(kExtensionName);
  return it != channel.extensions.end() && it->second.IsObject() && it->second.Has("placeholder") &&
         it->second.Get("placeholder").IsBool() && it->second.Get("placeholder").Get<bool>();
}

tinygltf::Value compressed_primitive_value(const CompressedPrimitive& primitive) {
  tinygltf::Value::Array clips;
  for (const CompressedClip& clip : primitive.clips) {
    tinygltf::Value::Object object;
    object["animation"] = tinygltf::Value(clip.animation);
    object["times"] = tinygltf::Value(clip.times);
    object["interpolation"] = tinygltf::Value(std::string(clip.step ? "STEP" : "LINEAR"));
    clips.emplace_back(std::move(object));
  }
  tinygltf::Value::Object object;
  object["bufferView"] = tinygltf::Value(primitive.buffer_view);
  if (primitive.morph_targets)
    object["morphTargets"] = tinygltf::Value(true);
  else
    object["clips"] = tinygltf::Value(std::move(clips));
  return tinygltf::Value(std::move(object));
}

tinygltf::Value draco_primitive_value(const DracoPrimitive& primitive) {
  tinygltf::Value::Object attributes;
  for (const auto& [semantic, id] : primitive.attributes) attributes[semantic] = tinygltf::Value(id);
  tinygltf::Value::Object object;
  object["bufferView"] = tinygltf::Value(primitive.buffer_view);
  object["attributes"] = tinygltf::Value(std::move(attributes));
  return tinygltf::Value(std::move(object));
}

tinygltf::Value compressed_animation_value(const CompressedAnimation& animation) {
  tinygltf::Value::Array samplers;
  for (int sampler : animation.samplers) samplers.emplace_back(sampler);
  tinygltf::Value::Object object;
  object["bufferView"] = tinygltf::Value(animation.buffer_view);
  object["samplers"] = tinygltf::Value(std::move(samplers));
  return tinygltf::Value(std::move(object));
}

tinygltf::Value placeholder_value() {
  tinygltf::Value::Object object;
  object["placeholder"] = tinygltf::Value(true);
  return tinygltf::Value(std::move(object));
}

void declare_extension(tinygltf::Model& model, const std::string& name, bool required) {
  if (!declares_extension(model, name)) model.extensionsUsed.push_back(name);
  if (required && std::find(model.extensionsRequired.begin(), model.extensionsRequired.end(), name) ==
                      model.extensionsRequired.end())
    model.extensionsRequired.push_back(name);
}

void undeclare_extension(tinygltf::Model& model, const std::string& name) {
  for (std::vector<std::string>* list : {&model.extensionsUsed, &model.extensionsRequired})
    list->erase(std::remove(list->begin(), list->end(), name), list->end());
}

bool declares_extension(const tinygltf::Model& model, const std::string& name) {
  return std::find(model.extensionsUsed.begin(), model.extensionsUsed.end(), name) != model.extensionsUsed.end();
}

Status read_compressed_mesh(const tinygltf::Model& model, size_t m, std::vector<CompressedPrimitive>& primitives,
                            int& node) {
  primitives.clear();
  node = -1;
  for (const tinygltf::Primitive& primitive : model.meshes[m].primitives) {
    auto it = primitive.extensions.find(kExtensionName);
    if (it == primitive.extensions.end()) continue;
    primitives.emplace_back();
    SEGMORPH_RETURN_IF_ERROR(parse_compressed_primitive(it->second, primitives.back()));
  }
  if (primitives.empty()) return Status::Ok();
  const std::string what = "mesh " + std::to_string(m);
  if (primitives.size() != model.meshes[m].primitives.size())
    return Status(StatusCode::bad_data, what + ": some primitives are compressed and some are not");
  for (const tinygltf::Primitive& primitive : model.meshes[m].primitives)
    if (primitive.mode != -1 && primitive.mode != TINYGLTF_MODE_TRIANGLES)
      return Status(StatusCode::bad_data, what + ": a compressed primitive must be a triangle list (mode 4)");
  for (const tinygltf::Node& user : model.nodes)
    if (user.mesh == int(m) && user.skin >= 0)
      return Status(StatusCode::bad_data, what + ": the node of a compressed mesh must not have a skin");
  const bool targets = primitives[0].morph_targets;
  for (const CompressedPrimitive& other : primitives)
    if (other.morph_targets != targets)
      return Status(StatusCode::bad_data, what + ": some primitives keep morph targets and some play clips");
  if (targets) return Status::Ok();
  std::vector<int> users;
  for (size_t n = 0; n < model.nodes.size(); ++n)
    if (model.nodes[n].mesh == int(m)) users.push_back(int(n));
  if (users.size() != 1)
    return Status(StatusCode::bad_data, what + ": a compressed mesh must be used by exactly one node");
  std::vector<int> animations;
  for (const CompressedClip& clip : primitives[0].clips) {
    if (size_t(clip.animation) >= model.animations.size())
      return Status(StatusCode::bad_data, what + ": a clip names an animation that does not exist");
    if (std::find(animations.begin(), animations.end(), clip.animation) != animations.end())
      return Status(StatusCode::bad_data, what + ": two clips name the same animation");
    animations.push_back(clip.animation);
  }
  // Rule 2: every primitive of the mesh has the same clips (each its own times).
  for (const CompressedPrimitive& other : primitives) {
    bool same = other.clips.size() == primitives[0].clips.size();
    for (size_t c = 0; same && c < other.clips.size(); ++c)
      same = other.clips[c].animation == primitives[0].clips[c].animation &&
             other.clips[c].step == primitives[0].clips[c].step;
    if (!same) return Status(StatusCode::bad_data, what + ": its primitives disagree on the clips");
  }
  node = users[0];
  return Status::Ok();
}

}  // namespace segmorph
