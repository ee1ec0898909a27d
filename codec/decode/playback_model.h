// A version-4 stream's model as a player evaluates it, on a GPU or in float32 on a CPU (spec/bitstream.md 8.5 and
// 8.7.1; docs/runtime.md, "Playing the model"): what does not depend on the frame (the welding, each welded vertex's
// clusters and weights, the clusters' centroids and bases, the coefficients) once, and per frame the parameters a
// frame is linear in (every cluster's affine map, every basis vector's value). Frame f of the stream is
//   X[v] = Σ_j ω_j (A_kj(f) (x_v − c_kj) + t_kj(f)) + Σ_i q_i b_(first + i)(f)
// over the pairs (k_j, ω_j) of v's welded vertex and the m vectors of its own cluster's basis. Because positions are
// linear in A, t and b, a blend of frames (a cross-fade, an interpolation) is the model at the blended parameters.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "decode/frame_decoder.h"
#include "segmorph/status.h"

namespace segmorph {

// Every welded vertex blends at most this many clusters: its own and up to 3 extra (spec 5.6).
constexpr size_t kModelPairs = 4;

// The frame-independent part, in the shapes of the C API (include/segmorph/decoder_c.h, segmorph_decoder_model_*).
struct PlaybackModel {
  size_t vertex_count = 0, welded_count = 0, cluster_count = 0, frame_count = 0;
  // Basis values per frame: the first `stream_vectors` vectors of the stream's basis (as many as a cluster uses),
  // then each kBasisOwn cluster's own vectors, in cluster order.
  size_t stream_vectors = 0, basis_count = 0;
  size_t max_basis_size = 0, max_pairs = 0;
  std::vector<uint32_t> welded;         // V: the welded vertex of each vertex
  std::vector<uint32_t> pair_cluster;   // W × 4: the own cluster first, then the extra ones; unused pairs: the own
  std::vector<float> pair_weight;       // W × 4: the pairs' weights (unused pairs: 0)
  std::vector<float> centroid;          // K × 3
  std::vector<uint32_t> cluster_basis;  // K × 2: the first basis value the cluster reads, and its m (0: no basis)
  std::vector<uint32_t> coefficient_offset;  // W + 1: in coefficient vectors
  std::vector<float> coefficients;      // coefficient vectors × 3: vector i of w at (offset[w] + i) × 3, x y z
};

// The model of the loop's stream (a version-4 one: loop.transform() is not null).
PlaybackModel playback_model(const StreamContent& content, const FrameLoop& loop);

// Frames first .. first + count − 1 (of the stream)'s parameters: motion K × 12 floats per frame (row r of cluster k's
// [A | t] at k × 12 + r × 4: A r0, A r1, A r2, t r), basis N floats per frame.
void playback_motion(const FrameLoop& loop, size_t first, size_t count, float* out);
void playback_basis(const PlaybackModel& model, const StreamContent& content, const FrameLoop& loop, size_t first,
                    size_t count, float* out);

// The positions (V × 3) at one set of parameters (motion K × 12, basis N floats: a frame's, or a blend of frames'),
// in float32 in the order of docs/runtime.md's vertex shader, each operation rounded: per pair with a nonzero weight,
// d = x − c, y_r = ((A_r0 d_0 + A_r1 d_1) + A_r2 d_2) + t_r, p = p + ω y; then r = r + q_i b_i over the own cluster's
// vectors; X = p + r. base: the base mesh's V × 3 positions.
void evaluate_playback_model(const PlaybackModel& model, const float* base, const float* motion, const float* basis,
                             float* out);

// A box (min x y z, max x y z) that holds every vertex of every frame of the stream, from the model and the
// parameters without reconstructing frames: per frame, each cluster's map applied to the box of x − c over the
// vertices that blend it, widened by the largest sum of |ω| of a vertex (1 where weights are in [0, 1]), plus the
// largest residual Σ_i max|q_i| |b_i(f)| of a cluster; with a margin for float rounding.
void playback_bounds(const PlaybackModel& model, const StreamContent& content, const FrameLoop& loop,
                     const float* base, float box[6]);

}  // namespace segmorph
