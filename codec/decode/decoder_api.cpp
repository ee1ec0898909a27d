// The runtime decoder's C++ API (include/segmorph/decoder.h) over the codec's own decoder (frame_decoder.h,
// track_decoder.h): argument checks, copies of what the caller lends, and no exception past the API.
#include "segmorph/decoder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "common/stream_format.h"
#include "common/topology.h"
#include "common/track_format.h"
#include "common/track_set.h"
#include "decode/frame_decoder.h"
#include "decode/normals.h"
#include "decode/playback_model.h"
#include "decode/track_decoder.h"

namespace segmorph {

static_assert(SEGMORPH_STREAM_VERSION_MIN == format::kOldestVersion &&
                  SEGMORPH_STREAM_VERSION_MAX == format::kNewestVersion,
              "include/segmorph/version.h names the stream versions codec/common/stream_format.h defines");
static_assert(SEGMORPH_TRACK_STREAM_VERSION == track_format::kVersion,
              "include/segmorph/version.h names the track stream version codec/common/track_format.h defines");

namespace {

Status invalid(const std::string& message) { return Status(StatusCode::invalid_argument, message); }

// Runs `f` (returning a Status) with allocation failures turned into a Status: no exception crosses the API.
template <typename F>
Status guarded(F f) {
#if defined(__cpp_exceptions)
  try {
    return f();
  } catch (const std::bad_alloc&) {
    return Status(StatusCode::out_of_memory, "out of memory");
  }
#else
  return f();
#endif
}

// Bounds on a track layout (decode_track_stream): every value costs the track stream at least one adaptive binary
// decision, and none costs less than log2(2048 / 2017) bits, so a stream of n bytes holds fewer than 364 (n + 8)
// values (spec/README.md, "Coded tracks"), and no layout may claim more than 2^26.
constexpr uint64_t kMaxValuesPerByte = 364, kMaxTrackValues = uint64_t(1) << 26;

// The layout's value count (samplers only) and time count, or false when the layout is invalid.
bool track_counts(const size_t* time_counts, size_t time_array_count, const TrackSamplerLayout* samplers,
                  size_t sampler_count, uint64_t& values, uint64_t& times) {
  values = times = 0;
  if ((time_array_count > 0 && !time_counts) || (sampler_count > 0 && !samplers)) return false;
  if (time_array_count > kMaxTrackValues || sampler_count > kMaxTrackValues) return false;
  std::vector<bool> used(time_array_count, false);
  for (size_t s = 0; s < sampler_count; ++s) {
    const TrackSamplerLayout& sampler = samplers[s];
    if (sampler.times >= time_array_count || sampler.path > uint32_t(TrackPathCode::weights)) return false;
    const TrackPathCode path = TrackPathCode(sampler.path);
    const uint32_t components = path == TrackPathCode::rotation ? 4 : path == TrackPathCode::weights ? 0 : 3;
    if (components != 0 ? sampler.components != components : sampler.components < 1) return false;
    const uint64_t keys = time_counts[sampler.times];
    if (keys < 1 || keys > kMaxTrackValues || sampler.components > kMaxTrackValues) return false;
    values += keys * sampler.components;
    if (values > kMaxTrackValues) return false;
    used[sampler.times] = true;
  }
  // Every time array is some sampler's (as the glTF layout makes them), so the times are no more than the values.
  for (size_t i = 0; i < time_array_count; ++i) {
    if (!used[i]) return false;
    times += time_counts[i];
  }
  return true;
}

}  // namespace

struct AnimationDecoder::State {
  std::vector<uint8_t> stream;
  std::vector<float> base;
  std::vector<uint32_t> triangles;
  FrameDecoder decoder;
  // decode_frame decodes a block of frames at a time (the frame loop's fast path: two in versions 1 to 3, up to
  // TransformBlocks::kMaxFrames in version 4) and keeps those after the first here for the next calls:
  // pending_count of them, frame pending_frame of clip pending_clip the next, at pending[pending_next × V × 3].
  std::vector<float> pending;
  size_t pending_count = 0, pending_next = 0;
  size_t pending_clip = 0, pending_frame = 0;
  bool has_pending() const { return pending_count > 0; }
  // The version-4 model in float32, made when first asked for.
  std::unique_ptr<PlaybackModel> model;
  // The surface normals turn on, made when first asked for: the stream's welding and the base surface's normals.
  std::unique_ptr<WeldedTopology> surface;
  std::vector<double> base_surface_normals;
};

AnimationDecoder::AnimationDecoder() = default;
AnimationDecoder::~AnimationDecoder() = default;
AnimationDecoder::AnimationDecoder(AnimationDecoder&&) noexcept = default;
AnimationDecoder& AnimationDecoder::operator=(AnimationDecoder&&) noexcept = default;

void AnimationDecoder::set_threads(size_t threads) { threads_ = threads; }

Status AnimationDecoder::open(const void* stream, size_t stream_size, const float* positions, size_t vertex_count,
                              const uint32_t* indices, size_t index_count) {
  close();
  if (stream_size > 0 && !stream) return invalid("the stream is null");
  if (vertex_count > 0 && !positions) return invalid("the base positions are null");
  if (index_count > 0 && !indices) return invalid("the indices are null");
  if (vertex_count > SIZE_MAX / 3 / sizeof(float)) return invalid("the vertex count is too large");
  if (index_count % 3 != 0) return invalid("the index count is not a multiple of 3 (triangles)");
  for (size_t i = 0; i < index_count; ++i)
    if (indices[i] >= vertex_count)
      return invalid("index " + std::to_string(i) + " (" + std::to_string(indices[i]) + ") is not below the vertex count (" +
                     std::to_string(vertex_count) + ")");
  const Status status = guarded([&] {
    auto state = std::make_unique<State>();
    const uint8_t* bytes = static_cast<const uint8_t*>(stream);
    state->stream.assign(bytes, bytes + stream_size);
    state->base.assign(positions, positions + vertex_count * 3);
    state->triangles.assign(indices, indices + index_count);
    SEGMORPH_RETURN_IF_ERROR(
        state->decoder.open(state->stream.data(), state->stream.size(), state->base, state->triangles));
    state_ = std::move(state);
    return Status::Ok();
  });
  return status;
}

void AnimationDecoder::close() { state_.reset(); }

bool AnimationDecoder::is_open() const { return state_ != nullptr; }

int AnimationDecoder::stream_version() const { return state_ ? state_->decoder.version() : 0; }

bool AnimationDecoder::lossless() const {
  return state_ && (state_->decoder.content().flags & format::kFlagLossless) != 0;
}

size_t AnimationDecoder::vertex_count() const { return state_ ? state_->decoder.content().vertex_count : 0; }

size_t AnimationDecoder::clip_count() const { return state_ ? state_->decoder.content().clip_frames.size() : 0; }

size_t AnimationDecoder::frame_count(size_t clip) const {
  return clip < clip_count() ? state_->decoder.content().clip_frames[clip] : 0;
}

size_t AnimationDecoder::total_frame_count() const { return state_ ? state_->decoder.content().frame_count() : 0; }

size_t AnimationDecoder::clip_floats(size_t clip) const { return frame_count(clip) * vertex_count() * 3; }

size_t AnimationDecoder::next_clip() const {
  if (!state_) return 0;
  return state_->has_pending() ? state_->pending_clip : state_->decoder.next_clip();
}

size_t AnimationDecoder::next_frame() const {
  if (!state_) return 0;
  return state_->has_pending() ? state_->pending_frame : state_->decoder.next_frame();
}

Status AnimationDecoder::seek(size_t clip) {
  if (!state_) return invalid("no stream is open");
  if (clip >= clip_count())
    return invalid("no clip " + std::to_string(clip) + " (the stream has " + std::to_string(clip_count()) + ")");
  State& state = *state_;
  state.pending_count = 0;
  return guarded([&] { return state.decoder.seek(clip); });
}

Status AnimationDecoder::decode_clip(size_t clip, float* destination, size_t destination_floats) {
  SEGMORPH_RETURN_IF_ERROR(seek(clip));
  const size_t floats = clip_floats(clip);
  if (!destination) return invalid("the destination is null");
  if (destination_floats < floats)
    return invalid("the destination holds " + std::to_string(destination_floats) + " floats, the clip needs " +
                   std::to_string(floats));
  State& state = *state_;
  state.pending_count = 0;
  return guarded([&] { return state.decoder.decode_frames(frame_count(clip), destination, threads_); });
}

Status AnimationDecoder::decode_targets(float* destination, size_t destination_floats) {
  if (!state_) return invalid("no stream is open");
  if (clip_count() != 1)
    return Status(StatusCode::bad_data, "the stream of kept morph targets must hold one clip; this one has " +
                                            std::to_string(clip_count()));
  SEGMORPH_RETURN_IF_ERROR(decode_clip(0, destination, destination_floats));
  const std::vector<float>& base = state_->base;
  const size_t frame_floats = base.size();
  for (size_t t = 0, targets = frame_count(0); t < targets; ++t) {
    float* target = destination + t * frame_floats;
    for (size_t i = 0; i < frame_floats; ++i) target[i] = target[i] - base[i];
  }
  return Status::Ok();
}

Status AnimationDecoder::decode_frame(float* destination, size_t destination_floats) {
  if (!state_) return invalid("no stream is open");
  const size_t frame_floats = vertex_count() * 3;
  if (!destination) return invalid("the destination is null");
  if (destination_floats < frame_floats)
    return invalid("the destination holds " + std::to_string(destination_floats) + " floats, a frame needs " +
                   std::to_string(frame_floats));
  State& state = *state_;
  if (state.has_pending()) {
    std::memcpy(destination, &state.pending[state.pending_next * frame_floats], frame_floats * sizeof(float));
    ++state.pending_next, ++state.pending_frame, --state.pending_count;
    return Status::Ok();
  }
  FrameDecoder& decoder = state.decoder;
  if (decoder.next_clip() >= clip_count())
    return invalid("every frame of the stream is decoded (seek to a clip to decode again)");
  return guarded([&] {
    const size_t count = std::min(decoder.frames_left_in_clip(), decoder.block_frames());
    if (count == 1) return decoder.decode(1, destination);
    state.pending.resize(count * frame_floats);
    const size_t clip = decoder.next_clip(), frame = decoder.next_frame() + 1;
    SEGMORPH_RETURN_IF_ERROR(decoder.decode(count, state.pending.data()));
    std::memcpy(destination, state.pending.data(), frame_floats * sizeof(float));
    state.pending_count = count - 1, state.pending_next = 1;
    state.pending_clip = clip, state.pending_frame = frame;
    return Status::Ok();
  });
}

namespace {

Status short_destination(const char* what, size_t given, size_t needed) {
  return invalid(std::string(what) + " holds " + std::to_string(given) + " values, the model needs " +
                 std::to_string(needed));
}

}  // namespace

// The stream's welding as a topology, and the base mesh's surface normals on it (made on first use).
Status AnimationDecoder::prepare_surface() {
  if (!state_) return invalid("no stream is open");
  State& state = *state_;
  if (state.surface) return Status::Ok();
  return guarded([&] {
    const StreamContent& content = state.decoder.content();
    auto surface = std::make_unique<WeldedTopology>(
        welded_topology(content.welded_index, content.welded_count, state.triangles));
    state.base_surface_normals = welded_vertex_normals(state.base.data(), *surface);
    state.surface = std::move(surface);
    return Status::Ok();
  });
}

Status AnimationDecoder::turn_normals(const float* normals, const float* frames, size_t frame_count,
                                      float* destination, size_t destination_floats) {
  SEGMORPH_RETURN_IF_ERROR(prepare_surface());
  const size_t frame_floats = vertex_count() * 3;
  if (!normals && frame_floats > 0) return invalid("the normals are null");
  if (!frames && frame_count > 0 && frame_floats > 0) return invalid("the frames are null");
  if (frame_floats > 0 && frame_count > SIZE_MAX / frame_floats) return invalid("the frame count is too large");
  if (!destination && frame_count * frame_floats > 0) return invalid("the destination is null");
  if (destination_floats < frame_count * frame_floats)
    return invalid("the destination holds " + std::to_string(destination_floats) + " floats, the frames need " +
                   std::to_string(frame_count * frame_floats));
  const State& state = *state_;
  return guarded([&] {
    for (size_t f = 0; f < frame_count; ++f)
      deform_normals(state.base_surface_normals, normals, frames + f * frame_floats, *state.surface,
                     destination + f * frame_floats);
    return Status::Ok();
  });
}

Status AnimationDecoder::surface_normals(const float* positions, float* destination, size_t destination_floats) {
  SEGMORPH_RETURN_IF_ERROR(prepare_surface());
  const size_t floats = vertex_count() * 3;
  if (!destination && floats > 0) return invalid("the destination is null");
  if (destination_floats < floats)
    return invalid("the destination holds " + std::to_string(destination_floats) + " floats, the mesh needs " +
                   std::to_string(floats));
  const State& state = *state_;
  return guarded([&] {
    const std::vector<double> welded =
        positions ? welded_vertex_normals(positions, *state.surface) : state.base_surface_normals;
    const std::vector<uint32_t>& point = state.surface->welded_index;
    for (size_t v = 0; v < point.size(); ++v) {
      const double* n = &welded[size_t(point[v]) * 3];
      const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      const double scale = length > 0 && std::isfinite(length) ? 1 / length : 0;
      for (int c = 0; c < 3; ++c) destination[v * 3 + size_t(c)] = float(n[c] * scale);
    }
    return Status::Ok();
  });
}

Status AnimationDecoder::make_model() {
  if (!state_) return invalid("no stream is open");
  State& state = *state_;
  if (!state.decoder.content().transform)
    return Status(StatusCode::unsupported, "the stream is version " + std::to_string(state.decoder.version()) +
                                               ": its frames depend on earlier frames' residuals, only version-4 "
                                               "streams have a model (decode frames instead)");
  if (state.model) return Status::Ok();
  return guarded([&] {
    state.model = std::make_unique<PlaybackModel>(playback_model(state.decoder.content(), state.decoder.loop()));
    return Status::Ok();
  });
}

Status AnimationDecoder::model_info(ModelInfo& info) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  const PlaybackModel& model = *state_->model;
  info.vertex_count = model.vertex_count;
  info.welded_count = model.welded_count;
  info.cluster_count = model.cluster_count;
  info.frame_count = model.frame_count;
  info.basis_count = model.basis_count;
  info.coefficient_count = model.coefficients.size() / 3;
  info.max_basis_size = model.max_basis_size;
  info.max_pairs = model.max_pairs;
  return Status::Ok();
}

Status AnimationDecoder::model_welded(uint32_t* destination, size_t count) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  const PlaybackModel& model = *state_->model;
  if (!destination) return invalid("the destination is null");
  if (count < model.welded.size()) return short_destination("the destination", count, model.welded.size());
  std::copy(model.welded.begin(), model.welded.end(), destination);
  return Status::Ok();
}

Status AnimationDecoder::model_weights(uint32_t* clusters, float* weights, size_t count) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  const PlaybackModel& model = *state_->model;
  if (!clusters || !weights) return invalid("a destination is null");
  if (count < model.pair_cluster.size()) return short_destination("the destination", count, model.pair_cluster.size());
  std::copy(model.pair_cluster.begin(), model.pair_cluster.end(), clusters);
  std::copy(model.pair_weight.begin(), model.pair_weight.end(), weights);
  return Status::Ok();
}

Status AnimationDecoder::model_clusters(float* centroids, uint32_t* bases, size_t cluster_count) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  const PlaybackModel& model = *state_->model;
  if (!centroids || !bases) return invalid("a destination is null");
  if (cluster_count < model.cluster_count) return short_destination("the destination", cluster_count, model.cluster_count);
  std::copy(model.centroid.begin(), model.centroid.end(), centroids);
  std::copy(model.cluster_basis.begin(), model.cluster_basis.end(), bases);
  return Status::Ok();
}

Status AnimationDecoder::model_coefficients(uint32_t* offsets, size_t offset_count, float* coefficients,
                                            size_t float_count) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  const PlaybackModel& model = *state_->model;
  if (!offsets || (!coefficients && !model.coefficients.empty())) return invalid("a destination is null");
  if (offset_count < model.coefficient_offset.size())
    return short_destination("the offsets' destination", offset_count, model.coefficient_offset.size());
  if (float_count < model.coefficients.size())
    return short_destination("the coefficients' destination", float_count, model.coefficients.size());
  std::copy(model.coefficient_offset.begin(), model.coefficient_offset.end(), offsets);
  std::copy(model.coefficients.begin(), model.coefficients.end(), coefficients);
  return Status::Ok();
}

namespace {

// Frames first .. first + count − 1 of `frames`, `per_frame` values each, into a destination of `floats`.
Status frame_range(size_t first, size_t count, size_t frames, size_t per_frame, const float* destination,
                   size_t floats) {
  if (first > frames || count > frames - first)
    return invalid("frames " + std::to_string(first) + " to " + std::to_string(first) + " + " + std::to_string(count) +
                   " are not all in the stream's " + std::to_string(frames));
  if (!destination && count * per_frame > 0) return invalid("the destination is null");
  if (floats < count * per_frame) return short_destination("the destination", floats, count * per_frame);
  return Status::Ok();
}

}  // namespace

Status AnimationDecoder::model_motion(size_t first_frame, size_t frame_count, float* destination,
                                      size_t destination_floats) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  State& state = *state_;
  const PlaybackModel& model = *state.model;
  SEGMORPH_RETURN_IF_ERROR(frame_range(first_frame, frame_count, model.frame_count, model.cluster_count * 12,
                                       destination, destination_floats));
  if (frame_count > 0) playback_motion(state.decoder.loop(), first_frame, frame_count, destination);
  return Status::Ok();
}

Status AnimationDecoder::model_basis(size_t first_frame, size_t frame_count, float* destination,
                                     size_t destination_floats) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  State& state = *state_;
  const PlaybackModel& model = *state.model;
  SEGMORPH_RETURN_IF_ERROR(
      frame_range(first_frame, frame_count, model.frame_count, model.basis_count, destination, destination_floats));
  if (frame_count > 0)
    playback_basis(model, state.decoder.content(), state.decoder.loop(), first_frame, frame_count, destination);
  return Status::Ok();
}

Status AnimationDecoder::model_bounds(float box[6]) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  State& state = *state_;
  const PlaybackModel& model = *state.model;
  if (!box) return invalid("the box is null");
  return guarded([&] {
    playback_bounds(model, state.decoder.content(), state.decoder.loop(), state.base.data(), box);
    return Status::Ok();
  });
}

Status AnimationDecoder::evaluate_model(const float* motion, size_t motion_floats, const float* basis,
                                        size_t basis_floats, float* positions, size_t position_floats) {
  SEGMORPH_RETURN_IF_ERROR(make_model());
  State& state = *state_;
  const PlaybackModel& model = *state.model;
  if (!motion || (!basis && model.basis_count > 0) || !positions) return invalid("a parameter or the destination is null");
  if (motion_floats < model.cluster_count * 12)
    return short_destination("the motion", motion_floats, model.cluster_count * 12);
  if (basis_floats < model.basis_count) return short_destination("the basis values", basis_floats, model.basis_count);
  if (position_floats < model.vertex_count * 3)
    return short_destination("the destination", position_floats, model.vertex_count * 3);
  evaluate_playback_model(model, state.base.data(), motion, basis, positions);
  return Status::Ok();
}

size_t track_stream_floats(const size_t* time_counts, size_t time_array_count, const TrackSamplerLayout* samplers,
                           size_t sampler_count) {
  uint64_t values = 0, times = 0;
  if (!track_counts(time_counts, time_array_count, samplers, sampler_count, values, times)) return 0;
  return size_t(values + times);
}

Status decode_track_stream(const void* stream, size_t stream_size, const size_t* time_counts, size_t time_array_count,
                           const TrackSamplerLayout* samplers, size_t sampler_count, float* destination,
                           size_t destination_floats) {
  uint64_t values = 0, times = 0;
  if (stream_size > 0 && !stream) return invalid("the stream is null");
  if (!track_counts(time_counts, time_array_count, samplers, sampler_count, values, times))
    return invalid("the track layout is invalid (an empty or unused time array, a sampler naming a missing one, a path "
                   "above 3, a component count that does not fit its path, or more than 2^26 values)");
  if (values > kMaxValuesPerByte * (uint64_t(stream_size) + 8))
    return Status(StatusCode::bad_data, "the track layout claims more values than a stream of " +
                                            std::to_string(stream_size) + " bytes can hold");
  if (!destination && values + times > 0) return invalid("the destination is null");
  if (destination_floats < values + times)
    return invalid("the destination holds " + std::to_string(destination_floats) + " floats, the tracks need " +
                   std::to_string(values + times));
  return guarded([&] {
    TrackLayout layout;
    layout.time_counts.assign(time_counts, time_counts + time_array_count);
    for (size_t s = 0; s < sampler_count; ++s)
      layout.samplers.push_back({int(samplers[s].times), TrackPath(samplers[s].path), int(samplers[s].components)});
    TrackSet tracks;
    SEGMORPH_RETURN_IF_ERROR(decode_tracks(static_cast<const uint8_t*>(stream), stream_size, layout, tracks));
    float* out = destination;
    for (const std::vector<float>& keys : tracks.times) out = std::copy(keys.begin(), keys.end(), out);
    for (const TrackSampler& sampler : tracks.samplers) out = std::copy(sampler.values.begin(), sampler.values.end(), out);
    return Status::Ok();
  });
}

}  // namespace segmorph
