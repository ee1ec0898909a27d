// The pipeline API (include/segmorph/segmorph.h): segmorph::Model around tinygltf's, and info, bake, encode, decode
// and verify over the converter's stages.
#include "pipeline.h"

#include <cstdio>
#include <cstring>

#include "bake/bake.h"
#include "common/topology.h"
#include "decoding/decode_file.h"
#include "encoding/encode_file.h"
#include "file_names.h"
#include "gltf/load.h"
#include "gltf/output_file.h"
#include "gltf/save.h"
#include "verify/comparison.h"

namespace segmorph {

Model::Model() : data_(std::make_unique<Data>()) {}
Model::~Model() = default;
Model::Model(const Model& other) : data_(std::make_unique<Data>(*other.data_)) {}
Model& Model::operator=(const Model& other) {
  if (this != &other) *data_ = *other.data_;
  return *this;
}
Model::Model(Model&& other) noexcept : data_(std::move(other.data_)) { other.data_ = std::make_unique<Data>(); }
Model& Model::operator=(Model&& other) noexcept {
  std::swap(data_, other.data_);
  return *this;
}

Status Model::load(const std::string& path, Model& model, std::vector<std::string>* warnings) {
  return guarded([&] {
    model = Model();
    return load_gltf(path, model.data().gltf, warnings);
  });
}

Status Model::save(const std::string& path) {
  return guarded([&] { return save_gltf(data_->gltf, path); });
}

size_t Model::glb_size() const { return segmorph::glb_size(data_->gltf); }

namespace {

// The file at `path` and the files its buffers and images name.
std::vector<std::string> files_of(const std::string& path, const Model& model) {
  std::vector<std::string> files = {path};
  const size_t slash = path.find_last_of('/');
  const std::string directory = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  for (const tinygltf::Buffer& buffer : model.data().gltf.buffers)
    if (!buffer.uri.empty() && buffer.uri.rfind("data:", 0) != 0) files.push_back(directory + buffer.uri);
  for (const tinygltf::Image& image : model.data().gltf.images)
    if (!image.uri.empty() && image.uri.rfind("data:", 0) != 0) files.push_back(directory + image.uri);
  return files;
}

}  // namespace

size_t file_bytes(const std::string& path, const Model& model) {
  size_t total = 0;
  for (const std::string& file : files_of(path, model)) {
    std::FILE* handle = std::fopen(file.c_str(), "rb");
    if (!handle) continue;
    std::fseek(handle, 0, SEEK_END);
    const long size = std::ftell(handle);
    std::fclose(handle);
    total += size > 0 ? size_t(size) : 0;
  }
  return total;
}

bool writes_over(const std::string& output, const std::string& input_path, const Model& input) {
  std::vector<std::string> written = {output};
  if (has_suffix(output, ".gltf"))
    written.push_back(output.substr(0, output.size() - 5) + ".bin");  // save() writes it beside
  for (const std::string& file : files_of(input_path, input))
    for (const std::string& out : written)
      if (same_file(file, out)) return true;
  return false;
}

Status analyze_model(const tinygltf::Model& model, const SampleSettings& settings, bool sample,
                     const Progress& progress, SampledFile& file) {
  tinygltf::Model copy = model;
  return analyze_model(std::move(copy), settings, sample, progress, file);
}

Status analyze_model(tinygltf::Model&& model, const SampleSettings& settings, bool sample, const Progress& progress,
                     SampledFile& file) {
  file.model = std::move(model);
  SEGMORPH_RETURN_IF_ERROR(decode_compressed_model(file.model, &file.decoded));
  SEGMORPH_RETURN_IF_ERROR(analyze_scene(file.model, file.scene));
  SEGMORPH_RETURN_IF_ERROR(check_frame_counts(file.model, file.scene, settings));
  if (!sample) return Status::Ok();
  const Scene& scene = file.scene;
  file.sampled.resize(scene.animated.size());
  for (size_t i = 0; i < scene.animated.size(); ++i) {
    const AnimatedNode& node = scene.animated[i];
    report_progress(progress, "sampling " + node_name(file.model, node.node) + " (" + std::to_string(i + 1) + "/" +
                                  std::to_string(scene.animated.size()) + "), " + std::to_string(node.clips.size()) +
                                  " clip" + (node.clips.size() == 1 ? "" : "s"));
    SEGMORPH_RETURN_IF_ERROR(sample_node(file.model, scene, node, settings, file.sampled[i]));
  }
  return Status::Ok();
}

PrimitiveError primitive_error(const tinygltf::Model& model, const PrimitiveComparison& compared) {
  PrimitiveError error;
  error.node = compared.node, error.node_name = model.nodes[size_t(compared.node)].name;
  error.mesh = compared.mesh, error.primitive = compared.primitive;
  error.vertices = compared.metrics.vertices, error.frames = compared.metrics.frames;
  error.kg_percent = compared.metrics.kg_percent;
  error.rmse_over_diagonal = compared.metrics.rmse_over_diagonal;
  error.max_error_over_diagonal = compared.metrics.max_error_over_diagonal;
  return error;
}

const char* mode_name(PrimitiveMode mode) {
  switch (mode) {
    case PrimitiveMode::frames: return "frames";
    case PrimitiveMode::kept_targets: return "kept_targets";
    case PrimitiveMode::kept_skin: return "kept_skin";
    case PrimitiveMode::rigid: return "rigid";
  }
  return "frames";
}

Status info(const Model& model, const SampleSettings& settings, InfoReport& report, const Progress& progress) {
  return guarded([&]() -> Status {
    const tinygltf::Model& encoded = model.data().gltf;
    SampledFile file;
    SEGMORPH_RETURN_IF_ERROR(analyze_model(encoded, settings, true, progress, file));
    report = InfoReport();
    report.animations = file.model.animations.size();
    for (const SampledNode& node : file.sampled) {
      const AnimatedNode& animated = *node.node;
      for (const SampledPrimitive& primitive : node.primitives) {
        const FrameSequence& first = primitive.clips[0];
        const WeldedTopology topology = weld_topology(primitive.clips);
        PrimitiveInfo out;
        out.node = animated.node;
        out.node_name = file.model.nodes[size_t(animated.node)].name;
        out.mesh = animated.mesh;
        out.primitive = primitive.primitive;
        out.kind = animated.kind();
        out.vertices = first.vertex_count;
        out.triangles = first.triangle_count();
        out.welded_vertices = topology.welded_count();
        out.connected_components = topology.component_count;
        // The decoded file may give the node a new mesh: the node's mesh in the encoded file holds the stream.
        const int node_mesh = size_t(out.node) < encoded.nodes.size() ? encoded.nodes[size_t(out.node)].mesh : -1;
        const StreamKind stream = compressed_stream_kind(encoded, node_mesh, out.primitive);
        out.stream_version = stream.version;
        out.kept_targets = stream.kept_targets;
        out.gpu_playable = stream.gpu_playable();
        for (size_t c = 0; c < primitive.clips.size(); ++c) {
          const FrameSequence& clip = primitive.clips[c];
          const Clip& source = file.scene.clips[size_t(animated.clips[c])];
          out.clips.push_back({source.animation, source.name, clip.frame_count,
                               double(clip.times.back()) - double(clip.times.front()),
                               clip.frame_count * clip.vertex_count * 3 * sizeof(float)});
        }
        report.primitives.push_back(std::move(out));
      }
    }
    return Status::Ok();
  });
}

Status bake(Model& model, const SampleSettings& settings, BakeReport* report, const Progress& progress) {
  const Status baked = guarded([&]() -> Status {
    // The model is baked in place (a copy would hold the input twice), and each node is sampled just before it is
    // baked: the frames of one node are held at a time.
    BakeReport local;
    BakeReport& out = report ? *report : local;
    out = BakeReport();
    SampledFile file;
    Status status = analyze_model(std::move(model.data().gltf), settings, false, progress, file);
    const Scene& scene = file.scene;
    out.nodes = scene.animated.size();
    auto sample = [&](size_t i, SampledNode& node) {
      report_progress(progress, "sampling and baking " + node_name(file.model, scene.animated[i].node) + " (" +
                                    std::to_string(i + 1) + "/" + std::to_string(scene.animated.size()) + ")");
      SEGMORPH_RETURN_IF_ERROR(sample_node(file.model, scene, scene.animated[i], settings, node));
      for (const FrameSequence& clip : node.primitives[0].clips) out.frames += clip.frame_count;
      return Status::Ok();
    };
    if (status.ok()) status = bake_model(file.model, scene, sample, baked_bytes(file.model, scene, settings));
    if (status.ok()) name_generator(file.model);
    model.data().gltf = status.ok() ? std::move(file.model) : tinygltf::Model();
    return status;
  });
  if (!baked.ok()) model.data().gltf = tinygltf::Model();  // also after an exception mid-bake
  return baked;
}

Status encode(const Model& input, const EncodeSettings& settings, Model& output, EncodeReport* report,
              const Progress& progress) {
  return guarded([&] { return encode(Model(input), settings, output, report, progress); });  // the copy too
}

Status encode(Model&& input, const EncodeSettings& settings, Model& output, EncodeReport* report,
              const Progress& progress) {
  return guarded([&]() -> Status {
    SampledFile file;
    tinygltf::Model gltf = std::move(input.data().gltf);
    input = Model();
    SEGMORPH_RETURN_IF_ERROR(analyze_model(std::move(gltf), settings.sampling, true, progress, file));
    EncodeReport local;
    tinygltf::Model encoded;
    SEGMORPH_RETURN_IF_ERROR(encode_sampled(file, settings, encoded, report ? *report : local, progress));
    output.data().gltf = std::move(encoded);
    return Status::Ok();
  });
}

Status decode(Model& model, DecodeReport* report, std::vector<DecodedFrames>* frames) {
  DecodeSettings one_thread;
  one_thread.threads = 1;
  return decode(model, one_thread, report, frames);
}

Status decode(Model& model, const DecodeSettings& settings, DecodeReport* report, std::vector<DecodedFrames>* frames) {
  return guarded([&]() -> Status {
    DecodedSizes sizes;
    SEGMORPH_RETURN_IF_ERROR(decode_compressed_model(model.data().gltf, &sizes, frames, settings.threads));
    if (sizes.primitives > 0 || sizes.coded_animations > 0) name_generator(model.data().gltf);
    if (report) *report = {sizes.animation_bytes, sizes.primitives, sizes.coded_animations};
    return Status::Ok();
  });
}

Status save_decoded_frames(const std::vector<DecodedFrames>& frames, const std::string& path) {
  return guarded([&]() -> Status {
    static_assert(sizeof(float) == 4, "binary32 floats");
    const uint16_t probe = 1;
    uint8_t first;
    std::memcpy(&first, &probe, 1);
    if (first != 1) return Status(StatusCode::unsupported, "raw frames are little-endian floats: this is a big-endian machine");
    size_t floats = 0;
    for (const DecodedFrames& primitive : frames)
      for (const DecodedFrames::Clip& clip : primitive.clips) floats += clip.positions.size();
    std::vector<float> all;
    all.reserve(floats);
    for (const DecodedFrames& primitive : frames)
      for (const DecodedFrames::Clip& clip : primitive.clips)
        all.insert(all.end(), clip.positions.begin(), clip.positions.end());
    return save_file(path, all.data(), all.size() * sizeof(float));
  });
}

Status verify(const Model& original, const Model& compressed, const SampleSettings& settings, VerifyReport& report,
              const Progress& progress) {
  report.failed_model = 1;  // also when it fails outside the steps below (an allocation)
  return guarded([&]() -> Status {
    SampledFile reference, other;
    report = VerifyReport();
    report.failed_model = 0;
    SEGMORPH_RETURN_IF_ERROR(analyze_model(original.data().gltf, settings, true, progress, reference));
    report.failed_model = 1;
    SEGMORPH_RETURN_IF_ERROR(analyze_model(compressed.data().gltf, settings, false, progress, other));
    report_progress(progress, "comparing at the frame times of the original");
    AnimationComparison comparison;
    SEGMORPH_RETURN_IF_ERROR(compare_animation(reference.model, reference.scene, reference.sampled, other.model,
                                               other.scene, comparison, false, nullptr, 0));  // every core
    report.failed_model = -1;
    report.vertices = comparison.vertices;
    report.frames = comparison.frames;
    report.vertex_frames = comparison.vertex_frames;
    report.kg_percent = comparison.worst.kg_percent;
    report.rmse_over_diagonal = comparison.worst.rmse_over_diagonal;
    report.max_error_over_diagonal = comparison.worst.max_error_over_diagonal;
    report.animation_bytes = other.decoded.animation_bytes;
    for (const PrimitiveComparison& compared : comparison.primitives)
      report.primitives.push_back(primitive_error(reference.model, compared));
    return Status::Ok();
  });
}

const PrimitiveError* VerifyReport::worst() const {
  const PrimitiveError* worst = nullptr;
  for (const PrimitiveError& primitive : primitives)
    if (!worst || primitive.kg_percent > worst->kg_percent) worst = &primitive;
  return worst;
}

VerifyBound exceeded_bound(const VerifyReport& report, size_t bytes, const VerifyBounds& bounds) {
  if (bounds.max_error >= 0 && report.kg_percent > bounds.max_error) return VerifyBound::max_error;
  if (bounds.max_bpvf >= 0 && bits_per_vertex_frame(bytes, report.vertex_frames) > bounds.max_bpvf)
    return VerifyBound::max_bpvf;
  return VerifyBound::none;
}

}  // namespace segmorph
