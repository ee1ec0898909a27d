/* segmorph's runtime decoder, C API: SEGMORPH_animation_compression streams turned into frames, for engines,
 * WebAssembly and any language with a C foreign-function interface. The same decoder as the C++ API (decoder.h);
 * docs/runtime.md shows both in use.
 *
 * Units and shapes: positions are 32-bit floats in the mesh's own space, vertex_count x 3 per frame, vertex-major
 * (x, y, z of vertex 0, then vertex 1, ...); a clip's frames follow each other. vertex_count is the number of the
 * base mesh's vertices as its Draco decoder returned them, in Draco's point order.
 *
 * Every function is safe on untrusted streams: nothing is read outside the bytes given, every count in a stream is
 * checked against the format's limits and the data before memory is sized by it, and a damaged stream gives
 * SEGMORPH_STATUS_BAD_DATA with a one-line message. There is no global state: a decoder is used by one thread at a
 * time, and any number of decoders may run on other threads. The decoder allocates its working memory with the C++
 * library's operator new (about 500 bytes per vertex, never the frames, which go where the caller says).
 *
 * The calls, for one primitive (error handling left out):
 *   segmorph_decoder* decoder = segmorph_decoder_create();
 *   segmorph_decoder_open(decoder, stream, stream_size, positions, vertex_count, indices, index_count);
 *   for (size_t clip = 0; clip < segmorph_decoder_clip_count(decoder); ++clip) {
 *     float* frames = malloc(segmorph_decode_clip_bound(decoder, clip) * sizeof(float));
 *     segmorph_decode_clip(decoder, clip, frames, segmorph_decode_clip_bound(decoder, clip));
 *   }
 *   segmorph_decoder_destroy(decoder);
 */
#ifndef SEGMORPH_DECODER_C_H
#define SEGMORPH_DECODER_C_H

#include <stddef.h>
#include <stdint.h>

#include "segmorph/version.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a call returns. The values are fixed: they never change meaning. */
typedef enum segmorph_status {
  SEGMORPH_STATUS_OK = 0,
  SEGMORPH_STATUS_INVALID_ARGUMENT = 1, /* an argument is unusable: a null pointer, a buffer too small, no such clip */
  SEGMORPH_STATUS_BAD_DATA = 3,         /* the stream is not valid: damaged, truncated, for another mesh */
  SEGMORPH_STATUS_UNSUPPORTED = 4,      /* a stream version or feature this decoder does not read */
  SEGMORPH_STATUS_INTERNAL = 7,         /* segmorph broke one of its own promises (a bug: please report it) */
  SEGMORPH_STATUS_OUT_OF_MEMORY = 8     /* an allocation failed */
} segmorph_status;

/* The name of a status ("ok", "bad data", ...): a static string. */
SEGMORPH_API const char* segmorph_status_name(segmorph_status status);

/* The version of the library linked (SEGMORPH_VERSION of its build), to compare with the header's. */
SEGMORPH_API int segmorph_version(void);

/* A decoder: opaque, created and freed by the caller, reused for any number of streams (one at a time). */
typedef struct segmorph_decoder segmorph_decoder;

/* A new decoder, or NULL when memory runs out. */
SEGMORPH_API segmorph_decoder* segmorph_decoder_create(void);

/* Frees the decoder and everything it holds. NULL is allowed. */
SEGMORPH_API void segmorph_decoder_destroy(segmorph_decoder* decoder);

/* The message of the last call on this decoder that failed, one line without a newline ("" after a success): what is
 * wrong, for a log or an exception. Valid until the next call on the decoder. */
SEGMORPH_API const char* segmorph_decoder_message(const segmorph_decoder* decoder);

/* Opens one primitive's animation stream (the bytes of the bufferView its SEGMORPH_animation_compression object
 * names) against the primitive's base mesh: positions (vertex_count x 3 floats, exactly as the Draco decoder
 * returned them) and indices (index_count = 3 x the triangle count, each < vertex_count; Draco's faces). Reads stream
 * versions SEGMORPH_STREAM_VERSION_MIN to SEGMORPH_STREAM_VERSION_MAX. The stream and the mesh are copied: the caller
 * may free them on return. Replaces what the decoder held; after a failure the decoder is closed. A stream that claims
 * more frames than its bytes can hold is refused here (each frame of each distinct base position costs at least 1/376
 * byte), so the frame counts and segmorph_decode_clip_bound() are safe to allocate by.
 * Returns INVALID_ARGUMENT (null pointers with nonzero counts, index_count not a multiple of 3, an index out of
 * range), BAD_DATA, UNSUPPORTED (a newer stream version) or OUT_OF_MEMORY. */
SEGMORPH_API segmorph_status segmorph_decoder_open(segmorph_decoder* decoder, const void* stream, size_t stream_size,
                                                   const float* positions, size_t vertex_count,
                                                   const uint32_t* indices, size_t index_count);

/* About the open stream; 0 when none is open. */
SEGMORPH_API int segmorph_decoder_stream_version(const segmorph_decoder* decoder);
SEGMORPH_API int segmorph_decoder_lossless(const segmorph_decoder* decoder); /* 1: the frames are exact */
SEGMORPH_API size_t segmorph_decoder_vertex_count(const segmorph_decoder* decoder);
SEGMORPH_API size_t segmorph_decoder_clip_count(const segmorph_decoder* decoder);
SEGMORPH_API size_t segmorph_decoder_frame_count(const segmorph_decoder* decoder, size_t clip); /* 0: no such clip */

/* How many floats a clip's frames take: frame count x vertex count x 3 (0 when there is no such clip). */
SEGMORPH_API size_t segmorph_decode_clip_bound(const segmorph_decoder* decoder, size_t clip);

/* Decodes every frame of `clip` into destination, which must have room for destination_floats floats, at least
 * segmorph_decode_clip_bound(decoder, clip). Afterwards the decoder stands at the next clip's first frame. On failure
 * the destination holds garbage. */
SEGMORPH_API segmorph_status segmorph_decode_clip(segmorph_decoder* decoder, size_t clip, float* destination,
                                                  size_t destination_floats);

/* For a primitive that keeps its morph targets (its extension object has "morphTargets": true): the targets' POSITION
 * displacements (frame_t - base, per coordinate in 32-bit float; target count x vertex count x 3 floats) into
 * destination, which must have room for destination_floats, at least segmorph_decode_clip_bound(decoder, 0).
 * BAD_DATA when the stream has more than one clip. */
SEGMORPH_API segmorph_status segmorph_decode_targets(segmorph_decoder* decoder, float* destination,
                                                     size_t destination_floats);

/* Frame by frame, in stream order (clip after clip): a player decodes frame f + 1 while f is shown and holds
 * vertex count x 3 floats instead of a whole clip. segmorph_decoder_next_clip() and _next_frame() say which frame
 * comes next (next_clip == clip count once the last frame is decoded). */
SEGMORPH_API size_t segmorph_decoder_next_clip(const segmorph_decoder* decoder);
SEGMORPH_API size_t segmorph_decoder_next_frame(const segmorph_decoder* decoder);

/* Decodes the next frame into destination (room for destination_floats floats, at least vertex count x 3) and
 * advances. Decoding the last frame also checks that the stream ends there. INVALID_ARGUMENT past the last frame. */
SEGMORPH_API segmorph_status segmorph_decode_frame(segmorph_decoder* decoder, float* destination,
                                                   size_t destination_floats);

/* Positions the decoder at the first frame of `clip`: O(vertex count) for a clip start already passed (the decoder
 * keeps a checkpoint of about 3 bytes per vertex at each), else the cost of decoding the frames before it. */
SEGMORPH_API segmorph_status segmorph_decoder_seek(segmorph_decoder* decoder, size_t clip);

/* Threads segmorph_decode_clip and segmorph_decode_targets may use for a version-4 stream, whose frames depend on no
 * other (versions 1 to 3 decode on the calling thread): 1, the default, or 0 for every hardware thread; the same
 * floats for any number. Started for each call and joined before it returns; kept across opens. A WebAssembly build
 * decodes on the calling thread whatever the setting. */
SEGMORPH_API segmorph_status segmorph_decoder_set_threads(segmorph_decoder* decoder, size_t threads);

/* Normals that turn with the surface, as segmorph decode writes them (AnimationDecoder::turn_normals in decoder.h):
 * the base mesh's normals (vertex count x 3 floats) turned to each of frame_count frames (frame_count x vertex count
 * x 3 positions) into destination (room for destination_floats, at least frame_count x vertex count x 3). */
SEGMORPH_API segmorph_status segmorph_decoder_turn_normals(segmorph_decoder* decoder, const float* normals,
                                                           const float* frames, size_t frame_count,
                                                           float* destination, size_t destination_floats);

/* Each vertex's unit geometric surface normal at its point (vertex count x 3 floats) in positions, or in the base
 * mesh when positions is null (AnimationDecoder::surface_normals). */
SEGMORPH_API segmorph_status segmorph_decoder_surface_normals(segmorph_decoder* decoder, const float* positions,
                                                              float* destination, size_t destination_floats);

/* The model of a version-4 stream, for a player that evaluates frames itself, on a GPU or a CPU, instead of decoding
 * them (docs/runtime.md, "Playing the model"; the same as the C++ API's AnimationDecoder::model_*, whose comments
 * give the formula). Frame f at vertex v of welded vertex w is
 *   X = sum_j w_j (A_kj(f) (x_v - c_kj) + t_kj(f)) + sum_i q_w,i b_(first_k + i)(f)
 * over w's (cluster, weight) pairs, its own cluster k first, and the m_k vectors of k's basis. Positions are linear in
 * the per-frame parameters A, t and b: a blend of frames is the model at the blended parameters. Every array is
 * float32 or uint32 in the shapes below, sized from segmorph_decoder_model_info(). Versions 1 to 3 have no model:
 * every segmorph_decoder_model_* call returns UNSUPPORTED, and a player decodes frames instead. */
typedef struct segmorph_model_info {
  size_t vertex_count;      /* V */
  size_t welded_count;      /* W */
  size_t cluster_count;     /* K */
  size_t frame_count;       /* F: every clip's frames, end to end */
  size_t basis_count;       /* N: the basis values of a frame */
  size_t coefficient_count; /* coefficient vectors, 3 floats each */
  size_t max_basis_size;    /* the largest m_k */
  size_t max_pairs;         /* the most clusters a welded vertex blends (1 to 4) */
} segmorph_model_info;

SEGMORPH_API segmorph_status segmorph_decoder_model_info(segmorph_decoder* decoder, segmorph_model_info* info);
/* V: the welded vertex of each vertex. */
SEGMORPH_API segmorph_status segmorph_decoder_model_welded(segmorph_decoder* decoder, uint32_t* destination,
                                                           size_t count);
/* W x 4 each: per welded vertex its pairs, the own cluster first; unused pairs are (own cluster, weight 0). */
SEGMORPH_API segmorph_status segmorph_decoder_model_weights(segmorph_decoder* decoder, uint32_t* clusters,
                                                            float* weights, size_t count);
/* K x 3 centroids, and K x 2: the index of cluster k's first value in a frame's basis values, and m_k (0: none). */
SEGMORPH_API segmorph_status segmorph_decoder_model_clusters(segmorph_decoder* decoder, float* centroids,
                                                             uint32_t* bases, size_t cluster_count);
/* W + 1 offsets (in vectors) and coefficient_count x 3 floats: vector i of welded vertex w at (offsets[w] + i) x 3. */
SEGMORPH_API segmorph_status segmorph_decoder_model_coefficients(segmorph_decoder* decoder, uint32_t* offsets,
                                                                 size_t offset_count, float* coefficients,
                                                                 size_t float_count);
/* Frames first_frame .. first_frame + frame_count - 1: K x 12 floats each (cluster k's [A | t] row by row at k x 12:
 * A r0, A r1, A r2, t r for row r) ... */
SEGMORPH_API segmorph_status segmorph_decoder_model_motion(segmorph_decoder* decoder, size_t first_frame,
                                                           size_t frame_count, float* destination,
                                                           size_t destination_floats);
/* ... and N floats each, the basis values. */
SEGMORPH_API segmorph_status segmorph_decoder_model_basis(segmorph_decoder* decoder, size_t first_frame,
                                                          size_t frame_count, float* destination,
                                                          size_t destination_floats);
/* A box (min x, y, z, max x, y, z) holding every vertex of every frame, from the model, without decoding frames. */
SEGMORPH_API segmorph_status segmorph_decoder_model_bounds(segmorph_decoder* decoder, float* box);
/* The model's V x 3 positions at one set of parameters (K x 12 motion floats, N basis values: a frame's or a blend):
 * the float32 reference of the vertex shader in docs/runtime.md. */
SEGMORPH_API segmorph_status segmorph_decoder_model_evaluate(segmorph_decoder* decoder, const float* motion,
                                                             size_t motion_floats, const float* basis,
                                                             size_t basis_floats, float* positions,
                                                             size_t position_floats);

/* Track streams (spec/tracks.md): an animation's coded keyframe samplers. The glTF JSON gives the layout
 * (spec/README.md, "Coded tracks"): each distinct time array's key count, and per coded sampler its time array, path
 * (0 translation, 1 rotation, 2 scale, 3 weights) and component count (3, 4 for rotations, the target count for
 * weights). */
typedef struct segmorph_track_sampler {
  uint32_t times;
  uint32_t path;
  uint32_t components;
} segmorph_track_sampler;

/* How many floats the decoded tracks of this layout take: every time array's keys, then every sampler's key count x
 * components values. 0 when the layout is invalid or claims more than 2^26 values. */
SEGMORPH_API size_t segmorph_decode_tracks_bound(const size_t* time_counts, size_t time_array_count,
                                                 const segmorph_track_sampler* samplers, size_t sampler_count);

/* Decodes a track stream laid out as given into destination (room for destination_floats floats, at least
 * segmorph_decode_tracks_bound(...)): time array 0's keys in seconds, time array 1's, ..., then sampler 0's values
 * (key by key, component by component), sampler 1's, ... The decoder is used for its message only (it may have a
 * stream open, which stays). BAD_DATA for a layout that claims more values than the stream's bytes can hold (checked
 * before anything is allocated) and for a stream that disagrees with its layout. */
SEGMORPH_API segmorph_status segmorph_decode_tracks(segmorph_decoder* decoder, const void* stream, size_t stream_size,
                                                    const size_t* time_counts, size_t time_array_count,
                                                    const segmorph_track_sampler* samplers, size_t sampler_count,
                                                    float* destination, size_t destination_floats);

#ifdef __cplusplus
}
#endif

#endif
