#include "decode/playback_model.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/stream_format.h"

namespace segmorph {

PlaybackModel playback_model(const StreamContent& content, const FrameLoop& loop) {
  const TransformResiduals* transform = loop.transform();
  assert(transform != nullptr);
  PlaybackModel model;
  model.vertex_count = content.vertex_count;
  model.welded_count = content.welded_count;
  model.cluster_count = content.cluster_count;
  model.frame_count = content.frame_count();
  model.welded = content.welded_index;

  // The clusters: centroids, and where each one's vectors start in a frame's basis values.
  const size_t K = model.cluster_count;
  model.centroid.resize(K * 3);
  for (size_t i = 0; i < K * 3; ++i) model.centroid[i] = float(loop.motion().centroid[i]);
  for (size_t k = 0; k < K; ++k)
    if (content.basis_source[k] == format::kBasisStream)
      model.stream_vectors = std::max<size_t>(model.stream_vectors, content.basis_size[k]);
  model.cluster_basis.assign(K * 2, 0);
  size_t next = model.stream_vectors;
  for (size_t k = 0; k < K; ++k) {
    const uint32_t m = content.basis_size[k];
    model.max_basis_size = std::max<size_t>(model.max_basis_size, m);
    if (content.basis_source[k] == format::kBasisOwn) {
      model.cluster_basis[k * 2] = uint32_t(next);
      next += m;
    }
    model.cluster_basis[k * 2 + 1] = content.basis_source[k] == format::kBasisNone ? 0 : m;
  }
  model.basis_count = next;

  // Per welded vertex: its pairs, padded to four, and its coefficients as (x, y, z) per vector.
  const ClusterWeights& weights = loop.weights();
  const size_t W = model.welded_count;
  model.pair_cluster.resize(W * kModelPairs);
  model.pair_weight.assign(W * kModelPairs, 0.0f);
  for (size_t w = 0; w < W; ++w) {
    const uint32_t begin = weights.offset[w], end = weights.offset[w + 1];
    assert(end - begin <= kModelPairs);
    model.max_pairs = std::max<size_t>(model.max_pairs, end - begin);
    for (size_t j = 0; j < kModelPairs; ++j) {
      const bool used = begin + j < end;
      model.pair_cluster[w * kModelPairs + j] = used ? weights.cluster[begin + j] : content.labels[w];
      model.pair_weight[w * kModelPairs + j] = used ? float(weights.weight[begin + j]) : 0.0f;
    }
  }
  const std::vector<uint64_t>& offsets = transform->offsets();
  const std::vector<double>& scaled = transform->scaled();
  model.coefficient_offset.resize(W + 1);
  model.coefficients.resize(size_t(offsets[W]));
  for (size_t w = 0; w < W; ++w) {
    const uint64_t at = offsets[w], m = (offsets[w + 1] - at) / 3;
    model.coefficient_offset[w] = uint32_t(at / 3);
    float* out = &model.coefficients[size_t(at)];
    for (uint64_t i = 0; i < m; ++i)
      for (uint64_t a = 0; a < 3; ++a) out[i * 3 + a] = float(scaled[size_t(at + a * m + i)]);
  }
  model.coefficient_offset[W] = uint32_t(offsets[W] / 3);
  return model;
}

void playback_motion(const FrameLoop& loop, size_t first, size_t count, float* out) {
  const TransformBlocks& blocks = *loop.blocks();
  const size_t clusters = loop.motion().cluster_count;
  for (size_t f = first; f < first + count; ++f)
    for (size_t k = 0; k < clusters; ++k)
      for (size_t j = 0; j < 12; ++j) *out++ = float(blocks.transform(k, j)[f]);
}

void playback_basis(const PlaybackModel& model, const StreamContent& content, const FrameLoop& loop, size_t first,
                    size_t count, float* out) {
  const TransformResiduals& transform = *loop.transform();
  const size_t stride = transform.stride();
  for (size_t f = first; f < first + count; ++f, out += model.basis_count) {
    for (size_t i = 0; i < model.stream_vectors; ++i) out[i] = float(transform.stream_basis()[i * stride + f]);
    for (size_t k = 0; k < model.cluster_count; ++k) {
      if (content.basis_source[k] != format::kBasisOwn) continue;
      const size_t m = content.basis_size[k];
      const double* own = transform.basis(k) + f;
      float* to = out + model.cluster_basis[k * 2];
      for (size_t i = 0; i < m; ++i) to[i] = float(own[i * stride]);
    }
  }
}

void evaluate_playback_model(const PlaybackModel& model, const float* base, const float* motion, const float* basis,
                             float* out) {
  for (size_t v = 0; v < model.vertex_count; ++v) {
    const size_t w = model.welded[v];
    const float* x = base + v * 3;
    float p[3] = {0.0f, 0.0f, 0.0f};
    for (size_t j = 0; j < kModelPairs; ++j) {
      const float omega = model.pair_weight[w * kModelPairs + j];
      if (omega == 0.0f) continue;
      const size_t k = model.pair_cluster[w * kModelPairs + j];
      const float* c = &model.centroid[k * 3];
      const float d[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
      for (size_t r = 0; r < 3; ++r) {
        const float* row = motion + k * 12 + r * 4;
        const float y = ((row[0] * d[0] + row[1] * d[1]) + row[2] * d[2]) + row[3];
        p[r] = p[r] + omega * y;
      }
    }
    const size_t k = model.pair_cluster[w * kModelPairs];
    const uint32_t first = model.cluster_basis[k * 2], m = model.cluster_basis[k * 2 + 1];
    const float* q = &model.coefficients[size_t(model.coefficient_offset[w]) * 3];
    float r[3] = {0.0f, 0.0f, 0.0f};
    for (uint32_t i = 0; i < m; ++i) {
      const float b = basis[first + i];
      for (size_t a = 0; a < 3; ++a) r[a] = r[a] + q[i * 3 + a] * b;
    }
    for (size_t a = 0; a < 3; ++a) out[v * 3 + a] = p[a] + r[a];
  }
}

namespace {

// An axis-aligned box, in double.
struct Box {
  double low[3] = {INFINITY, INFINITY, INFINITY}, high[3] = {-INFINITY, -INFINITY, -INFINITY};
  bool empty() const { return !(low[0] <= high[0]); }
  void add(const double* x) {
    for (size_t a = 0; a < 3; ++a) low[a] = std::min(low[a], x[a]), high[a] = std::max(high[a], x[a]);
  }
};

// Row r of the affine map y = A (x − c) + t = A x + (t − A c) over the box of x: its interval [low, high].
void map_row(const float* row, const double* centroid, const Box& x, double& low, double& high) {
  double centre = row[3], half = 0.0;
  for (size_t c = 0; c < 3; ++c) {
    centre += double(row[c]) * (0.5 * (x.low[c] + x.high[c]) - centroid[c]);
    half += std::fabs(double(row[c])) * 0.5 * (x.high[c] - x.low[c]);
  }
  low = centre - half, high = centre + half;
}

}  // namespace

void playback_bounds(const PlaybackModel& model, const StreamContent& content, const FrameLoop& loop,
                     const float* base, float box[6]) {
  // A welded vertex w of own cluster k with extra pairs (j, ω_j) is, since its weights sum to 1,
  //   X = y_k(x) + Σ_j ω_j (y_j(x) − y_k(x)) + r,
  // y the clusters' maps: its own map's image, plus its extra weights times the difference of two neighbouring
  // maps at x (small, even where the weights lie far outside [0, 1], as least-squares weights do), plus its
  // residual. Per own cluster: the box of x over its members; per group of vertices with the same own cluster and
  // the same extra clusters: the box of x over them and each extra's largest |ω|; per frame, each map and each
  // difference of maps applied to its box.
  const size_t K = model.cluster_count, W = model.welded_count;
  const std::vector<float>& welded = loop.welded();
  const std::vector<double>& centroid = loop.motion().centroid;
  std::vector<Box> members(K);
  struct Group {
    uint32_t own;
    uint32_t extra[kModelPairs - 1];
    double weight[kModelPairs - 1];  // the largest |ω| of each extra
    size_t count;
    Box x;
  };
  std::vector<Group> groups;
  std::vector<std::vector<size_t>> groups_of(K);  // per own cluster: its groups
  std::vector<size_t> largest_at(K + 1, 0);  // cluster k's largest |q| at largest[largest_at[k] + i × 3 + a]
  for (size_t k = 0; k < K; ++k) largest_at[k + 1] = largest_at[k] + size_t(model.cluster_basis[k * 2 + 1]) * 3;
  std::vector<double> largest(largest_at[K], 0.0);
  for (size_t w = 0; w < W; ++w) {
    const double x[3] = {welded[w * 3], welded[w * 3 + 1], welded[w * 3 + 2]};
    const uint32_t k = content.labels[w];
    members[k].add(x);
    Group key{k, {0, 0, 0}, {0, 0, 0}, 0, Box()};
    for (size_t j = 1; j < kModelPairs; ++j) {
      const float omega = model.pair_weight[w * kModelPairs + j];
      const uint32_t extra = model.pair_cluster[w * kModelPairs + j];
      if (omega == 0.0f || extra == k) continue;  // nothing, or y_k − y_k
      key.extra[key.count] = extra, key.weight[key.count] = std::fabs(double(omega)), ++key.count;
    }
    if (key.count > 0) {
      std::vector<size_t>& list = groups_of[k];
      auto same = [&](size_t g) {
        return groups[g].count == key.count && std::equal(key.extra, key.extra + key.count, groups[g].extra);
      };
      auto found = std::find_if(list.begin(), list.end(), same);
      if (found == list.end()) {
        list.push_back(groups.size());
        groups.push_back(key);
        found = list.end() - 1;
      }
      Group& group = groups[*found];
      group.x.add(x);
      for (size_t j = 0; j < key.count; ++j) group.weight[j] = std::max(group.weight[j], key.weight[j]);
    }
    const size_t m = model.cluster_basis[k * 2 + 1];
    const float* q = &model.coefficients[size_t(model.coefficient_offset[w]) * 3];
    for (size_t i = 0; i < m * 3; ++i)
      largest[largest_at[k] + i] = std::max(largest[largest_at[k] + i], std::fabs(double(q[i])));
  }

  Box total;
  std::vector<float> motion(K * 12), basis(model.basis_count);
  std::vector<double> spread(K);  // per own cluster: the largest Σ_j |ω_j (y_j − y_k)| of a group, on one axis
  const double origin[3] = {0, 0, 0};
  for (size_t f = 0; f < model.frame_count; ++f) {
    playback_motion(loop, f, 1, motion.data());
    playback_basis(model, content, loop, f, 1, basis.data());
    for (size_t a = 0; a < 3; ++a) {
      std::fill(spread.begin(), spread.end(), 0.0);
      for (const Group& group : groups) {
        double sum = 0.0;
        for (size_t j = 0; j < group.count; ++j) {
          // y_j − y_k = (A_j − A_k) x + (t_j − A_j c_j) − (t_k − A_k c_k): a map of its own over the group's box.
          const float* rj = &motion[group.extra[j] * 12 + a * 4];
          const float* rk = &motion[group.own * 12 + a * 4];
          float row[4] = {0, 0, 0, 0};
          double offset = double(rj[3]) - double(rk[3]);
          for (size_t c = 0; c < 3; ++c) {
            row[c] = float(double(rj[c]) - double(rk[c]));
            offset += -double(rj[c]) * centroid[group.extra[j] * 3 + c] + double(rk[c]) * centroid[group.own * 3 + c];
          }
          double low, high;
          map_row(row, origin, group.x, low, high);
          sum += group.weight[j] * std::max(std::fabs(low + offset), std::fabs(high + offset));
        }
        spread[group.own] = std::max(spread[group.own], sum);
      }
      for (size_t k = 0; k < K; ++k) {
        if (members[k].empty()) continue;
        double low, high;
        map_row(&motion[k * 12 + a * 4], &centroid[k * 3], members[k], low, high);
        const size_t first = model.cluster_basis[k * 2], m = model.cluster_basis[k * 2 + 1];
        double residual = 0.0;
        for (size_t i = 0; i < m; ++i) residual += largest[largest_at[k] + i * 3 + a] * std::fabs(double(basis[first + i]));
        total.low[a] = std::min(total.low[a], low - spread[k] - residual);
        total.high[a] = std::max(total.high[a], high + spread[k] + residual);
      }
    }
  }
  // An axis no cluster bounds (no frames): the base's extent.
  for (size_t a = 0; a < 3; ++a)
    if (!(total.low[a] <= total.high[a]))
      for (size_t v = 0; v < model.vertex_count; ++v) {
        total.low[a] = std::min(total.low[a], double(base[v * 3 + a]));
        total.high[a] = std::max(total.high[a], double(base[v * 3 + a]));
      }
  // Float rounding (the model in float32, the decoder's double frames rounded once): a relative margin.
  double extent = 0.0;
  for (size_t a = 0; a < 3; ++a) extent = std::max(extent, total.high[a] - total.low[a]);
  for (size_t a = 0; a < 3; ++a) {
    const double margin = 1e-5 * (extent + std::fabs(total.low[a]) + std::fabs(total.high[a])) + 1e-30;
    box[a] = float(total.low[a] - margin);
    box[3 + a] = float(total.high[a] + margin);
  }
}

}  // namespace segmorph
