// segmorph's runtime decoder, C++ API: the SEGMORPH_animation_compression streams of one glTF file turned into
// frames, for an engine or a viewer that loads the glTF itself (tinygltf, cgltf, fastgltf, ...) and decodes its
// KHR_draco_mesh_compression base meshes with its own Draco. Needs the C++17 standard library only. The C API
// (decoder_c.h) is the same decoder for C, WebAssembly and other languages; docs/runtime.md shows both in use.
//
// Units and shapes: positions are binary32, in the mesh's own space, V × 3 per frame, vertex-major (x, y, z of
// vertex 0, then vertex 1, ...); frames follow each other (clip-major, then frame-major). V is the number of the base
// mesh's vertices as its Draco decoder returned them, in Draco's point order.
//
// Every function is safe on untrusted streams: nothing is read outside the bytes given, every count in a stream is
// checked against the format's limits and the data before memory is sized by it, and a damaged stream is refused
// with StatusCode::bad_data and a one-line message. There is no global state: a decoder object is used by one
// thread at a time, and any number of them may run on other threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "segmorph/status.h"
#include "segmorph/version.h"

namespace segmorph {

// Decodes one primitive's animation stream (the bytes of the bufferView its SEGMORPH_animation_compression object
// names; spec/bitstream.md) against the primitive's base mesh. Reads stream versions SEGMORPH_STREAM_VERSION_MIN to
// SEGMORPH_STREAM_VERSION_MAX, lossy and lossless, both residual codes.
//
// Two ways to decode, which give the same floats:
// - whole clips, decode_clip(): clip_floats(c) floats each, for a player that keeps every frame (as morph targets,
//   or in its own animation system);
// - frame by frame, decode_frame(): the next frame in stream order (clip after clip) into V × 3 floats, for a player
//   that decodes frame f + 1 while frame f is shown and holds O(V) floats instead of F × V × 3. seek() goes to the
//   first frame of a clip: to a clip start already passed it costs O(V) (a checkpoint), to a later one it costs
//   decoding the frames before it.
//
// Memory: the decoder holds the stream (a copy), the base mesh (a copy), the stream's motion (12 integers per frame
// and cluster), per-vertex state (about 500 bytes per vertex) and a checkpoint per clip start passed (about 3 bytes
// per vertex); never a clip's frames. It reconstructs a few frames at a time (two; eight in stream version 4, whose
// coefficients it also holds: docs/runtime.md), and decode_frame() keeps the ones after the frame it returns until
// they are asked for.
class SEGMORPH_API AnimationDecoder {
 public:
  AnimationDecoder();
  ~AnimationDecoder();
  AnimationDecoder(AnimationDecoder&&) noexcept;
  AnimationDecoder& operator=(AnimationDecoder&&) noexcept;
  AnimationDecoder(const AnimationDecoder&) = delete;
  AnimationDecoder& operator=(const AnimationDecoder&) = delete;

  // Reads the stream's head (clips, frame counts, clusters, motion, weights) against the base mesh: positions
  // (vertex_count × 3 floats, exactly as the Draco decoder returned them) and indices (index_count = 3 × the
  // triangle count, each < vertex_count; Draco's faces). The stream and the mesh are copied: the caller may free
  // them on return. Replaces whatever the decoder held; after a failure the decoder is closed. A stream that claims
  // more frames than its bytes can hold is refused here (each frame of each distinct base position costs at least
  // 1/376 byte), so the frame counts, and clip_floats(), are safe to allocate by.
  // Errors: invalid_argument (null pointers with nonzero counts, index_count not a multiple of 3, an index out of
  // range), bad_data (not a valid stream, or one for another vertex count), unsupported (a stream version this
  // decoder does not read).
  Status open(const void* stream, size_t stream_size, const float* positions, size_t vertex_count,
              const uint32_t* indices, size_t index_count);

  // Forgets the stream and frees what the decoder holds.
  void close();
  bool is_open() const;

  // About the open stream (0 or false when none is open).
  int stream_version() const;  // 1 to 4
  bool lossless() const;       // the frames are the encoder's input, bit for bit
  size_t vertex_count() const;
  size_t clip_count() const;
  size_t frame_count(size_t clip) const;  // 0 for a clip that does not exist
  size_t total_frame_count() const;       // all clips
  // Floats a clip's frames take: frame_count(clip) × vertex_count() × 3.
  size_t clip_floats(size_t clip) const;

  // Decodes every frame of `clip` into destination[0 .. clip_floats(clip)); destination_floats must be at least
  // that. Afterwards the decoder stands at the next clip's first frame. On bad data the destination holds garbage.
  Status decode_clip(size_t clip, float* destination, size_t destination_floats);

  // Threads that decode_clip() and decode_targets() may use for a version-4 stream, whose frames depend on no other
  // (versions 1 to 3 decode on the calling thread): 1, the default, or 0 for every hardware thread. The frames are the
  // same floats for any number. Threads are started for each call and joined before it returns. A WebAssembly build
  // decodes on the calling thread whatever the setting. Kept across open().
  void set_threads(size_t threads);
  size_t threads() const { return threads_; }

  // For a primitive that keeps its morph targets (spec/README.md, "Kept morph targets": its extension object has
  // "morphTargets": true and the stream one clip of T frames, T the primitive's target count): the targets' POSITION
  // displacements, frame_t − base per coordinate in binary32, T × vertex_count() × 3 floats into destination, which
  // holds destination_floats (at least clip_floats(0)). Fails (bad_data) when the stream has more than one clip.
  Status decode_targets(float* destination, size_t destination_floats);

  // Frame by frame. The next frame to decode (next_clip() == clip_count() once the last one is decoded).
  size_t next_clip() const;
  size_t next_frame() const;  // within next_clip()
  // Decodes the next frame into destination[0 .. vertex_count() × 3) (destination_floats at least that) and
  // advances. Decoding the stream's last frame also checks that the stream ends there. invalid_argument past the
  // last frame (seek first).
  Status decode_frame(float* destination, size_t destination_floats);
  // Positions the decoder at the first frame of `clip` (invalid_argument when there is no such clip).
  Status seek(size_t clip);

  // Normals that turn with the surface (spec/README.md, "Normals and tangents"): what segmorph decode writes, and
  // what the web plugins show. Each vertex's base normal (normals: V × 3, the base mesh's NORMAL) is turned by the
  // smallest rotation taking the area-weighted geometric normal of the surface around its point in the base mesh to
  // the one in the frame, then normalized; where either surface normal vanishes it is only normalized. Vertices the
  // stream welds (equal positions in every frame of the encoded animation) are one point. frames: frame_count × V ×
  // 3 positions (decoded frames, or the base plus targets' displacements, or any shape of the mesh); destination: room
  // for frame_count × V × 3 floats (destination_floats).
  Status turn_normals(const float* normals, const float* frames, size_t frame_count, float* destination,
                      size_t destination_floats);
  // V × 3: each vertex's unit geometric surface normal at its point (area-weighted over the triangles around it;
  // zero where none is), in `positions` (V × 3; the base mesh when null): what a shader that turns normals itself
  // needs of the base mesh.
  Status surface_normals(const float* positions, float* destination, size_t destination_floats);

  // The model of a version-4 stream (spec/bitstream.md 8.5 and 8.7.1), for a player that evaluates frames itself,
  // on a GPU or a CPU, instead of decoding them (docs/runtime.md, "Playing the model"). Frame f of the stream, at
  // vertex v of welded vertex w, is
  //   X = Σ_j ω_j (A_kj(f) (x_v − c_kj) + t_kj(f)) + Σ_i q_w,i b_(first_k + i)(f)
  // over w's pairs (k_j, ω_j) (its own cluster k first) and the m_k vectors of its own cluster's basis: the same
  // per-vertex data for every frame, and positions linear in the per-frame parameters A, t and b, so a blend of
  // frames is the model at the blended parameters. Every array is float32 (or uint32), in the shapes below, each
  // filled by one call into a buffer the caller sized from model_info(). In float32 the model's positions differ from
  // the decoded (double-evaluated) frames by rounding only (docs/runtime.md gives the measured difference).
  // Streams of versions 1 to 3 have no such model (each frame depends on earlier frames' residuals): every model_*
  // call returns unsupported for them, and a player decodes frames instead.
  struct ModelInfo {
    size_t vertex_count = 0;       // V
    size_t welded_count = 0;       // W
    size_t cluster_count = 0;      // K
    size_t frame_count = 0;        // F: every clip's frames, end to end (clip c starts at the sum of those before)
    size_t basis_count = 0;        // N: the basis values of a frame
    size_t coefficient_count = 0;  // coefficient vectors, 3 floats each (x, y, z)
    size_t max_basis_size = 0;     // the largest m_k
    size_t max_pairs = 0;          // the most clusters a welded vertex blends (1 to 4)
  };
  Status model_info(ModelInfo& info);
  // V: the welded vertex of each vertex.
  Status model_welded(uint32_t* destination, size_t count);
  // W × 4 each: per welded vertex its pairs, the own cluster first, then the extra clusters in stream order; unused
  // pairs are (own cluster, weight 0).
  Status model_weights(uint32_t* clusters, float* weights, size_t count);
  // K × 3 centroids (c_k) and K × 2 bases: the index of cluster k's first value in a frame's basis values, and m_k
  // (0: no residuals).
  Status model_clusters(float* centroids, uint32_t* bases, size_t cluster_count);
  // W + 1 offsets (in vectors) and coefficient_count × 3 floats: vector i of welded vertex w at (offsets[w] + i) × 3
  // (x, y, z), i < m of its own cluster; each q × D of spec 8.7.1 rounded to float.
  Status model_coefficients(uint32_t* offsets, size_t offset_count, float* coefficients, size_t float_count);
  // Frames first_frame .. first_frame + frame_count − 1 of the stream: per frame K × 12 floats, cluster k's 3 × 4
  // [A | t] row by row at k × 12 (A r0, A r1, A r2, t r for row r) ...
  Status model_motion(size_t first_frame, size_t frame_count, float* destination, size_t destination_floats);
  // ... and N floats, the basis values b_n(f).
  Status model_basis(size_t first_frame, size_t frame_count, float* destination, size_t destination_floats);
  // A box holding every vertex of every frame (min x, y, z, then max x, y, z), from the model, without decoding
  // frames: conservative (each cluster's map applied to the box of its vertices, the largest residual), never
  // smaller than the frames' box.
  Status model_bounds(float box[6]);
  // The model's V × 3 positions at one set of parameters (motion: K × 12 floats, basis: N floats, as model_motion()
  // and model_basis() give them for a frame, or a blend of frames'): the float32 reference of the vertex shader in
  // docs/runtime.md, operation by operation.
  Status evaluate_model(const float* motion, size_t motion_floats, const float* basis, size_t basis_floats,
                        float* positions, size_t position_floats);

 private:
  Status make_model();  // the model of the open stream, made on first use (unsupported before version 4)
  Status prepare_surface();  // the welding and base surface turn_normals and surface_normals use, on first use

  struct State;
  std::unique_ptr<State> state_;
  size_t threads_ = 1;
};

// The track stream of an animation (spec/tracks.md): keyframe samplers of node translations, rotations, scales
// (and morph weights) quantized and range-coded. The glTF JSON gives its layout (spec/README.md, "Coded tracks"):
// the key count of each distinct time array, and per coded sampler its time array, path and component count.
enum class TrackPathCode : uint32_t { translation = 0, rotation = 1, scale = 2, weights = 3 };

struct TrackSamplerLayout {
  uint32_t times = 0;       // index of its time array
  uint32_t path = 0;        // a TrackPathCode
  uint32_t components = 3;  // 3 for translation and scale, 4 for rotation (x, y, z, w), the target count for weights
};

// Floats the decoded tracks of this layout take: every time array's keys, then every sampler's key count ×
// components values. 0 when the layout is invalid (an empty time array, a sampler naming a missing time array, a
// path above 3, a component count that does not fit its path) or claims more than 2^26 values.
SEGMORPH_API size_t track_stream_floats(const size_t* time_counts, size_t time_array_count,
                                        const TrackSamplerLayout* samplers, size_t sampler_count);

// Decodes a track stream laid out as given into destination (destination_floats at least track_stream_floats(...)):
// time array 0's keys (seconds), time array 1's, ..., then sampler 0's values (key by key, component by component),
// sampler 1's, ... Refuses (bad_data) a layout that claims more values than a stream of stream_size bytes can hold
// (364 per byte, spec/README.md) before allocating anything, and a stream that disagrees with its layout.
SEGMORPH_API Status decode_track_stream(const void* stream, size_t stream_size, const size_t* time_counts,
                                        size_t time_array_count, const TrackSamplerLayout* samplers,
                                        size_t sampler_count, float* destination, size_t destination_floats);

}  // namespace segmorph
