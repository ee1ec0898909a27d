// The runtime decoder's C API (include/segmorph/decoder_c.h): a handle around the C++ API's AnimationDecoder and the
// message of its last failure.
#include "segmorph/decoder_c.h"

#include <new>
#include <string>
#include <vector>

#include "segmorph/decoder.h"

struct segmorph_decoder {
  segmorph::AnimationDecoder decoder;
  std::string message;
};

namespace {

// The status of `status`, its message kept in the decoder (one line: the library's messages have no newline).
segmorph_status report(segmorph_decoder* decoder, const segmorph::Status& status) {
#if defined(__cpp_exceptions)
  try {
    decoder->message = status.message();
  } catch (const std::bad_alloc&) {
    decoder->message.clear();  // the status still says what happened
  }
#else
  decoder->message = status.message();
#endif
  switch (status.code()) {
    case segmorph::StatusCode::ok:
      return SEGMORPH_STATUS_OK;
    case segmorph::StatusCode::invalid_argument:
      return SEGMORPH_STATUS_INVALID_ARGUMENT;
    case segmorph::StatusCode::bad_data:
      return SEGMORPH_STATUS_BAD_DATA;
    case segmorph::StatusCode::unsupported:
      return SEGMORPH_STATUS_UNSUPPORTED;
    case segmorph::StatusCode::out_of_memory:
      return SEGMORPH_STATUS_OUT_OF_MEMORY;
    default:  // the decoder reports no other code
      return SEGMORPH_STATUS_INTERNAL;
  }
}

// More samplers than values a layout may claim (2^26) make an invalid layout; refused before they are copied.
constexpr size_t kMaxSamplers = size_t(1) << 26;

segmorph_status null_decoder() { return SEGMORPH_STATUS_INVALID_ARGUMENT; }

// The C++ API's copy of a C sampler layout; false when memory runs out.
bool cpp_layout(const segmorph_track_sampler* samplers, size_t count,
                std::vector<segmorph::TrackSamplerLayout>& layout) {
#if defined(__cpp_exceptions)
  try {
    layout.resize(count);
  } catch (const std::bad_alloc&) {
    return false;
  }
#else
  layout.resize(count);
#endif
  for (size_t s = 0; s < count; ++s) layout[s] = {samplers[s].times, samplers[s].path, samplers[s].components};
  return true;
}

}  // namespace

extern "C" {

const char* segmorph_status_name(segmorph_status status) {
  switch (status) {
    case SEGMORPH_STATUS_OK:
      return "ok";
    case SEGMORPH_STATUS_INVALID_ARGUMENT:
      return "invalid argument";
    case SEGMORPH_STATUS_BAD_DATA:
      return "bad data";
    case SEGMORPH_STATUS_UNSUPPORTED:
      return "unsupported";
    case SEGMORPH_STATUS_INTERNAL:
      return "internal error";
    case SEGMORPH_STATUS_OUT_OF_MEMORY:
      return "out of memory";
  }
  return "unknown status";
}

int segmorph_version(void) { return SEGMORPH_VERSION; }

segmorph_decoder* segmorph_decoder_create(void) { return new (std::nothrow) segmorph_decoder(); }

void segmorph_decoder_destroy(segmorph_decoder* decoder) { delete decoder; }

const char* segmorph_decoder_message(const segmorph_decoder* decoder) {
  return decoder ? decoder->message.c_str() : "the decoder is null";
}

segmorph_status segmorph_decoder_open(segmorph_decoder* decoder, const void* stream, size_t stream_size,
                                      const float* positions, size_t vertex_count, const uint32_t* indices,
                                      size_t index_count) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.open(stream, stream_size, positions, vertex_count, indices, index_count));
}

int segmorph_decoder_stream_version(const segmorph_decoder* decoder) {
  return decoder ? decoder->decoder.stream_version() : 0;
}

int segmorph_decoder_lossless(const segmorph_decoder* decoder) {
  return decoder && decoder->decoder.lossless() ? 1 : 0;
}

size_t segmorph_decoder_vertex_count(const segmorph_decoder* decoder) {
  return decoder ? decoder->decoder.vertex_count() : 0;
}

size_t segmorph_decoder_clip_count(const segmorph_decoder* decoder) {
  return decoder ? decoder->decoder.clip_count() : 0;
}

size_t segmorph_decoder_frame_count(const segmorph_decoder* decoder, size_t clip) {
  return decoder ? decoder->decoder.frame_count(clip) : 0;
}

size_t segmorph_decode_clip_bound(const segmorph_decoder* decoder, size_t clip) {
  return decoder ? decoder->decoder.clip_floats(clip) : 0;
}

segmorph_status segmorph_decode_clip(segmorph_decoder* decoder, size_t clip, float* destination,
                                     size_t destination_floats) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.decode_clip(clip, destination, destination_floats));
}

segmorph_status segmorph_decode_targets(segmorph_decoder* decoder, float* destination, size_t destination_floats) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.decode_targets(destination, destination_floats));
}

size_t segmorph_decoder_next_clip(const segmorph_decoder* decoder) {
  return decoder ? decoder->decoder.next_clip() : 0;
}

size_t segmorph_decoder_next_frame(const segmorph_decoder* decoder) {
  return decoder ? decoder->decoder.next_frame() : 0;
}

segmorph_status segmorph_decode_frame(segmorph_decoder* decoder, float* destination, size_t destination_floats) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.decode_frame(destination, destination_floats));
}

segmorph_status segmorph_decoder_seek(segmorph_decoder* decoder, size_t clip) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.seek(clip));
}

segmorph_status segmorph_decoder_set_threads(segmorph_decoder* decoder, size_t threads) {
  if (!decoder) return null_decoder();
  decoder->decoder.set_threads(threads);
  return report(decoder, segmorph::Status::Ok());
}

segmorph_status segmorph_decoder_model_info(segmorph_decoder* decoder, segmorph_model_info* info) {
  if (!decoder) return null_decoder();
  if (!info) return report(decoder, segmorph::Status(segmorph::StatusCode::invalid_argument, "the info is null"));
  segmorph::AnimationDecoder::ModelInfo model;
  const segmorph_status status = report(decoder, decoder->decoder.model_info(model));
  if (status == SEGMORPH_STATUS_OK)
    *info = {model.vertex_count,      model.welded_count,   model.cluster_count, model.frame_count,
             model.basis_count,       model.coefficient_count, model.max_basis_size, model.max_pairs};
  return status;
}

segmorph_status segmorph_decoder_turn_normals(segmorph_decoder* decoder, const float* normals, const float* frames,
                                              size_t frame_count, float* destination, size_t destination_floats) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.turn_normals(normals, frames, frame_count, destination, destination_floats));
}

segmorph_status segmorph_decoder_surface_normals(segmorph_decoder* decoder, const float* positions, float* destination,
                                                 size_t destination_floats) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.surface_normals(positions, destination, destination_floats));
}

segmorph_status segmorph_decoder_model_welded(segmorph_decoder* decoder, uint32_t* destination, size_t count) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.model_welded(destination, count));
}

segmorph_status segmorph_decoder_model_weights(segmorph_decoder* decoder, uint32_t* clusters, float* weights,
                                               size_t count) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.model_weights(clusters, weights, count));
}

segmorph_status segmorph_decoder_model_clusters(segmorph_decoder* decoder, float* centroids, uint32_t* bases,
                                                size_t cluster_count) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.model_clusters(centroids, bases, cluster_count));
}

segmorph_status segmorph_decoder_model_coefficients(segmorph_decoder* decoder, uint32_t* offsets, size_t offset_count,
                                                    float* coefficients, size_t float_count) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.model_coefficients(offsets, offset_count, coefficients, float_count));
}

segmorph_status segmorph_decoder_model_motion(segmorph_decoder* decoder, size_t first_frame, size_t frame_count,
                                              float* destination, size_t destination_floats) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.model_motion(first_frame, frame_count, destination, destination_floats));
}

segmorph_status segmorph_decoder_model_basis(segmorph_decoder* decoder, size_t first_frame, size_t frame_count,
                                             float* destination, size_t destination_floats) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.model_basis(first_frame, frame_count, destination, destination_floats));
}

segmorph_status segmorph_decoder_model_bounds(segmorph_decoder* decoder, float* box) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.model_bounds(box));
}

segmorph_status segmorph_decoder_model_evaluate(segmorph_decoder* decoder, const float* motion, size_t motion_floats,
                                                const float* basis, size_t basis_floats, float* positions,
                                                size_t position_floats) {
  if (!decoder) return null_decoder();
  return report(decoder, decoder->decoder.evaluate_model(motion, motion_floats, basis, basis_floats, positions,
                                                         position_floats));
}

size_t segmorph_decode_tracks_bound(const size_t* time_counts, size_t time_array_count,
                                    const segmorph_track_sampler* samplers, size_t sampler_count) {
  if ((sampler_count > 0 && !samplers) || sampler_count > kMaxSamplers) return 0;
  std::vector<segmorph::TrackSamplerLayout> layout;
  if (!cpp_layout(samplers, sampler_count, layout)) return 0;
  return segmorph::track_stream_floats(time_counts, time_array_count, layout.data(), sampler_count);
}

segmorph_status segmorph_decode_tracks(segmorph_decoder* decoder, const void* stream, size_t stream_size,
                                       const size_t* time_counts, size_t time_array_count,
                                       const segmorph_track_sampler* samplers, size_t sampler_count,
                                       float* destination, size_t destination_floats) {
  if (!decoder) return null_decoder();
  if (sampler_count > 0 && !samplers)
    return report(decoder, segmorph::Status(segmorph::StatusCode::invalid_argument, "the samplers are null"));
  if (sampler_count > kMaxSamplers)
    return report(decoder, segmorph::Status(segmorph::StatusCode::invalid_argument, "the track layout has too many samplers"));
  std::vector<segmorph::TrackSamplerLayout> layout;
  if (!cpp_layout(samplers, sampler_count, layout))
    return report(decoder, segmorph::Status(segmorph::StatusCode::out_of_memory, "out of memory"));
  return report(decoder, segmorph::decode_track_stream(stream, stream_size, time_counts, time_array_count,
                                                       layout.data(), sampler_count, destination, destination_floats));
}

}  // extern "C"
