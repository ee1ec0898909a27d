#include "track_streams.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "accessor.h"
#include "common/track_set.h"
#include "decode/track_decoder.h"
#include "encode/track_encoder.h"
#include "segmorph/decoder.h"
#include "segmorph_extension.h"

namespace segmorph {
namespace {

// Bounds on what a coded animation may claim, checked before anything is allocated: every value costs the track
// stream at least one adaptive binary decision, and no decision costs less than log2(2048 / 2017) ≈ 0.022 bits,
// so a stream of n bytes holds fewer than 364 (n + 8) values.
constexpr size_t kMaxValuesPerByte = 364, kMaxCodedValues = size_t(1) << 26;

bool path_of(const std::string& name, TrackPath& path) {
  if (name == "translation") path = TrackPath::translation;
  else if (name == "rotation") path = TrackPath::rotation;
  else if (name == "scale") path = TrackPath::scale;
  else return false;
  return true;
}

int components_of(TrackPath path) { return path == TrackPath::rotation ? 4 : 3; }

// The path (and the first node) of the channels that play sampler `s`: false unless there is at least one and they
// agree on a translation, rotation or scale path.
bool sampler_path(const tinygltf::Animation& animation, int s, TrackPath& path, int& node) {
  bool found = false;
  for (const tinygltf::AnimationChannel& channel : animation.channels) {
    if (channel.sampler != s) continue;
    TrackPath this_path;
    if (!path_of(channel.target_path, this_path) || (found && this_path != path)) return false;
    if (!found) node = channel.target_node;
    path = this_path;
    found = true;
  }
  return found;
}

bool linear_or_step(const tinygltf::AnimationSampler& sampler) {
  return sampler.interpolation.empty() || sampler.interpolation == "LINEAR" || sampler.interpolation == "STEP";
}

// A sampler as the track stream takes it: false when its data does not fit (times not increasing, values not
// finite, a zero rotation), and it stays as it is.
bool read_sampler(const tinygltf::Model& model, const tinygltf::AnimationSampler& sampler, TrackPath path,
                  std::vector<float>& times, std::vector<float>& values) {
  const int width = components_of(path);
  int components = 0;
  if (!read_floats(model, sampler.input, "animation input", times).ok() ||
      !read_floats(model, sampler.output, "animation output", values, &components).ok() || components != width ||
      times.empty() || values.size() != times.size() * size_t(width))
    return false;
  for (size_t k = 0; k < times.size(); ++k) {
    if (!(std::isfinite(times[k]) && times[k] >= 0 && (k == 0 || times[k] > times[k - 1]))) return false;
    if (times[k] == 0) times[k] = 0.0f;  // -0 plays as +0; the stream codes times by their bits and takes +0 only
  }
  for (float value : values)
    if (!std::isfinite(value)) return false;
  if (path == TrackPath::rotation)
    for (size_t k = 0; k < times.size(); ++k) {
      double norm = 0;
      for (int c = 0; c < 4; ++c) norm += double(values[k * 4 + size_t(c)]) * values[k * 4 + size_t(c)];
      if (!(norm > 0.5 && norm < 2)) return false;  // not a rotation a viewer would play as it is
    }
  return true;
}

// An accessor without data: the track stream holds it.
int add_coded_accessor(tinygltf::Model& model, size_t count, int type, const std::vector<float>* bounds) {
  tinygltf::Accessor accessor;
  accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  accessor.count = count;
  accessor.type = type;
  if (bounds) {  // glTF requires them on an animation's input: its first and last key
    accessor.minValues = {double(bounds->front())};
    accessor.maxValues = {double(bounds->back())};
  }
  model.accessors.push_back(accessor);
  return int(model.accessors.size()) - 1;
}

// The node's own value of `path` (what plays when no channel moves it), or false when it has a matrix.
bool rest_value(const tinygltf::Node& node, TrackPath path, double rest[4]) {
  if (!node.matrix.empty()) return false;
  const std::vector<double>& own = path == TrackPath::translation ? node.translation
                                   : path == TrackPath::rotation  ? node.rotation
                                                                  : node.scale;
  const double identity[3][4] = {{0, 0, 0, 0}, {0, 0, 0, 1}, {1, 1, 1, 0}};
  const int width = components_of(path);
  if (!own.empty() && own.size() != size_t(width)) return false;
  for (int c = 0; c < width; ++c) rest[c] = own.empty() ? identity[int(path)][c] : own[size_t(c)];
  return true;
}

// Whether every key of a track is within half a step of the node's rest value (a rotation's or its negation):
// its channels play what the node holds anyway, to within the quantization, and can go.
bool holds_rest(const tinygltf::Model& model, int node, TrackPath path, const std::vector<float>& values, double step) {
  double rest[4];
  if (node < 0 || size_t(node) >= model.nodes.size() || !rest_value(model.nodes[size_t(node)], path, rest)) return false;
  const size_t width = size_t(components_of(path));
  for (size_t k = 0; k < values.size() / width; ++k) {
    bool same = true, negated = path == TrackPath::rotation;
    for (size_t c = 0; c < width; ++c) {
      same = same && std::abs(values[k * width + c] - rest[c]) <= step / 2;
      negated = negated && std::abs(values[k * width + c] + rest[c]) <= step / 2;
    }
    if (!same && !negated) return false;
  }
  return true;
}

Status compress_animation(tinygltf::Model& model, size_t a, const TrackStep& step_of, TrackReport& report) {
  tinygltf::Animation& animation = model.animations[a];
  TrackSet set;
  std::vector<double> steps;
  CompressedAnimation coded;
  std::map<std::vector<float>, int> distinct;  // time array → its index in set.times
  for (size_t s = 0; s < animation.samplers.size(); ++s) {
    const tinygltf::AnimationSampler& sampler = animation.samplers[s];
    TrackSampler track;
    int node = -1;
    std::vector<float> times;
    if (!linear_or_step(sampler) || !sampler_path(animation, int(s), track.path, node) ||
        !read_sampler(model, sampler, track.path, times, track.values))
      continue;
    track.components = components_of(track.path);
    const double step = step_of(track.path, node);
    if (holds_rest(model, node, track.path, track.values, step) && animation.channels.size() > 1) {
      // Its channels go (the sampler, then unused, goes when the file is written); one channel always stays.
      bool others = true;
      for (const tinygltf::AnimationChannel& channel : animation.channels)
        others = others && (channel.sampler != int(s) || channel.target_node == node);
      if (others) {
        std::vector<tinygltf::AnimationChannel> kept;
        for (const tinygltf::AnimationChannel& channel : animation.channels)
          if (channel.sampler != int(s)) kept.push_back(channel);
        if (!kept.empty()) {
          animation.channels = std::move(kept);
          ++report.dropped;
          continue;
        }
      }
    }
    auto found = distinct.emplace(times, int(set.times.size()));
    if (found.second) set.times.push_back(std::move(times));
    track.times = found.first->second;
    steps.push_back(step);
    set.samplers.push_back(std::move(track));
    coded.samplers.push_back(int(s));
  }
  if (set.samplers.empty()) return Status::Ok();
  std::vector<uint8_t> bytes;
  TrackSet decoded;
  // A track the stream cannot hold at these steps (values beyond its integer range) leaves the animation as it is.
  if (!encode_tracks(set, steps, bytes, decoded).ok()) return Status::Ok();

  std::vector<int> input(set.times.size());
  for (size_t t = 0; t < set.times.size(); ++t)
    input[t] = add_coded_accessor(model, set.times[t].size(), TINYGLTF_TYPE_SCALAR, &set.times[t]);
  for (size_t i = 0; i < set.samplers.size(); ++i) {
    tinygltf::AnimationSampler& sampler = animation.samplers[size_t(coded.samplers[i])];
    const TrackSampler& track = set.samplers[i];
    const size_t keys = set.times[size_t(track.times)].size();
    sampler.input = input[size_t(track.times)];
    sampler.output = add_coded_accessor(model, keys, track.components == 4 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3,
                                        nullptr);
    report.keys += keys;
  }
  AccessorWriter writer(model);
  coded.buffer_view = writer.add_view(bytes.data(), bytes.size(), 0);
  animation.extensions[kExtensionName] = compressed_animation_value(coded);
  report.samplers += set.samplers.size();
  report.bytes += bytes.size();
  return Status::Ok();
}

// The layout the JSON gives a coded animation's stream, checked: `inputs` receives each time array's accessor.
Status coded_layout(const tinygltf::Model& model, const tinygltf::Animation& animation, const CompressedAnimation& coded,
                    size_t stream_size, const std::string& what, TrackLayout& layout, std::vector<int>& inputs) {
  size_t values = 0;
  auto accessor_ok = [&](int index, bool input) {
    if (index < 0 || size_t(index) >= model.accessors.size()) return false;
    const tinygltf::Accessor& accessor = model.accessors[size_t(index)];
    return accessor.bufferView < 0 && !accessor.sparse.isSparse &&
           accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT && accessor.count >= 1 &&
           (!input || accessor.type == TINYGLTF_TYPE_SCALAR);
  };
  for (int s : coded.samplers) {
    if (size_t(s) >= animation.samplers.size())
      return Status(StatusCode::bad_data, what + ": a coded sampler does not exist");
    const tinygltf::AnimationSampler& sampler = animation.samplers[size_t(s)];
    TrackLayout::Sampler entry;
    int node = -1;
    if (!sampler_path(animation, s, entry.path, node))
      return Status(StatusCode::bad_data, what + ": coded sampler " + std::to_string(s) +
                                              " must move translations, rotations or scales alone");
    if (!linear_or_step(sampler))
      return Status(StatusCode::bad_data, what + ": coded sampler " + std::to_string(s) + " is not LINEAR or STEP");
    if (!accessor_ok(sampler.input, true) || !accessor_ok(sampler.output, false))
      return Status(StatusCode::bad_data, what + ": coded sampler " + std::to_string(s) +
                                              " needs FLOAT accessors without data");
    const tinygltf::Accessor& output = model.accessors[size_t(sampler.output)];
    entry.components = components_of(entry.path);
    if (output.type != (entry.components == 4 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3) ||
        output.count != model.accessors[size_t(sampler.input)].count)
      return Status(StatusCode::bad_data, what + ": coded sampler " + std::to_string(s) +
                                              "'s output disagrees with its input or path");
    const auto known = std::find(inputs.begin(), inputs.end(), sampler.input);
    entry.times = int(known - inputs.begin());
    if (known == inputs.end()) {
      inputs.push_back(sampler.input);
      layout.time_counts.push_back(model.accessors[size_t(sampler.input)].count);
    }
    values += output.count * size_t(entry.components);
    if (values > kMaxCodedValues || values > kMaxValuesPerByte * (stream_size + 8))
      return Status(StatusCode::bad_data, what + ": the coded samplers claim more keys than the stream can hold");
    layout.samplers.push_back(entry);
  }
  return Status::Ok();
}

}  // namespace

Status code_track_streams(tinygltf::Model& model, const TrackStep& step_of, TrackReport& report) {
  for (size_t a = 0; a < model.animations.size(); ++a)
    SEGMORPH_RETURN_IF_ERROR(compress_animation(model, a, step_of, report));
  if (report.samplers > 0) declare_extension(model, kExtensionName, true);
  return Status::Ok();
}

Status decode_tracks_in_model(tinygltf::Model& model, size_t* bytes, size_t* animations) {
  size_t total = 0, coded_animations = 0;
  for (size_t a = 0; a < model.animations.size(); ++a) {
    tinygltf::Animation& animation = model.animations[a];
    const auto it = animation.extensions.find(kExtensionName);
    if (it == animation.extensions.end()) continue;
    const std::string what = "animation " + std::to_string(a);
    CompressedAnimation coded;
    Status status = parse_compressed_animation(it->second, coded);
    if (!status.ok()) return Status(status.code(), what + ": " + status.message());
    const unsigned char* data = nullptr;
    size_t size = 0;
    SEGMORPH_RETURN_IF_ERROR(buffer_view_bytes(model, coded.buffer_view, what + " track stream", &data, &size));
    TrackLayout layout;
    std::vector<int> inputs;
    SEGMORPH_RETURN_IF_ERROR(coded_layout(model, animation, coded, size, what, layout, inputs));
    // Through the runtime decoder (include/segmorph/decoder.h): the times of each array, then each sampler's values.
    std::vector<TrackSamplerLayout> samplers;
    for (const TrackLayout::Sampler& sampler : layout.samplers)
      samplers.push_back({uint32_t(sampler.times), uint32_t(sampler.path), uint32_t(sampler.components)});
    const size_t floats =
        track_stream_floats(layout.time_counts.data(), layout.time_counts.size(), samplers.data(), samplers.size());
    std::vector<float> decoded(floats);
    status = decode_track_stream(data, size, layout.time_counts.data(), layout.time_counts.size(), samplers.data(),
                                 samplers.size(), decoded.data(), decoded.size());
    if (!status.ok()) return Status(status.code(), what + ": " + status.message());
    AccessorWriter writer(model);
    const float* next = decoded.data();
    std::vector<int> written(layout.time_counts.size());
    for (size_t t = 0; t < written.size(); ++t) {
      written[t] = writer.add_floats(next, layout.time_counts[t], TINYGLTF_TYPE_SCALAR, true, 0);
      next += layout.time_counts[t];
    }
    for (size_t i = 0; i < coded.samplers.size(); ++i) {
      const TrackLayout::Sampler& track = layout.samplers[i];
      const size_t keys = layout.time_counts[size_t(track.times)];
      tinygltf::AnimationSampler& sampler = animation.samplers[size_t(coded.samplers[i])];
      sampler.input = written[size_t(track.times)];
      sampler.output = writer.add_floats(next, keys, track.components == 4 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3,
                                         false, 0);
      next += keys * size_t(track.components);
    }
    animation.extensions.erase(it);
    total += size;
    ++coded_animations;
  }
  if (bytes) *bytes = total;
  if (animations) *animations = coded_animations;
  return Status::Ok();
}

}  // namespace segmorph
