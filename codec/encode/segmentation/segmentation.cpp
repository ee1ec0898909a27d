#include "encode/segmentation/segmentation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <mutex>
#include <numeric>
#include <set>
#include <utility>

namespace segmorph {
namespace {

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void join(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// Band of μ among ascending `levels`: the number of levels <= μ.
size_t band_of(double mu, const std::vector<double>& levels) {
  return size_t(std::upper_bound(levels.begin(), levels.end(), mu) - levels.begin());
}

// Number of connected pieces of each band of one mesh component.
std::vector<size_t> pieces_per_band(const std::vector<uint32_t>& vertices, const std::vector<double>& mu,
                                    const VertexAdjacency& adjacency, const std::vector<double>& levels,
                                    std::vector<uint32_t>& band, UnionFind& pieces) {
  for (uint32_t v : vertices) {
    band[v] = uint32_t(band_of(mu[v], levels));
    pieces.parent[v] = v;
  }
  for (uint32_t v : vertices)
    for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i)
      if (band[adjacency.neighbour[i]] == band[v]) pieces.join(v, adjacency.neighbour[i]);
  std::vector<size_t> count(levels.size() + 1, 0);
  for (uint32_t v : vertices)
    if (pieces.find(v) == v) ++count[band[v]];
  return count;
}

// Per-cluster sufficient statistics of the affine fit: with x̃ the homogeneous base position (shifted by a
// common origin for conditioning), G = Σ x̃ x̃ᵀ, and per frame B_f = Σ x̃ y_fᵀ and s_f = Σ ‖y_f‖². The
// least-squares residual of a set over all frames is Σ_f s_f − tr(B_fᵀ G⁺ B_f); statistics of a union are sums.
struct FitStatistics {
  Eigen::Matrix4d gram = Eigen::Matrix4d::Zero();
  std::vector<Eigen::Matrix<double, 4, 3>> moments;  // F
  std::vector<double> energy;                        // F
  size_t size = 0;

  double residual() const {
    Eigen::CompleteOrthogonalDecomposition<Eigen::Matrix4d> decomposition(gram);
    decomposition.setThreshold(1e-10);
    const Eigen::Matrix4d inverse = decomposition.pseudoInverse();
    double sum = 0;
    for (size_t f = 0; f < moments.size(); ++f)
      sum += energy[f] - (moments[f].transpose() * inverse * moments[f]).trace();
    return std::max(sum, 0.0);
  }
  void add(const FitStatistics& other) {
    gram += other.gram;
    for (size_t f = 0; f < moments.size(); ++f) {
      moments[f] += other.moments[f];
      energy[f] += other.energy[f];
    }
    size += other.size;
  }
};

}  // namespace

Clusters compact(const std::vector<uint32_t>& label) {
  Clusters clusters;
  std::vector<uint32_t> number(label.size(), UINT32_MAX);
  clusters.label.resize(label.size());
  for (size_t v = 0; v < label.size(); ++v) {
    uint32_t& n = number[label[v]];
    if (n == UINT32_MAX) n = uint32_t(clusters.count++);
    clusters.label[v] = n;
  }
  return clusters;
}


Clusters clusters_from_levels(const std::vector<double>& mu, const WeldedTopology& topology,
                              const VertexAdjacency& adjacency, const MorseBands& bands,
                              const MorseSettings& settings) {
  const size_t vertex_count = topology.welded_count();
  std::vector<uint32_t> band(vertex_count);
  for (size_t w = 0; w < vertex_count; ++w) band[w] = uint32_t(band_of(mu[w], bands.levels[topology.component[w]]));
  UnionFind pieces(vertex_count);
  for (size_t w = 0; w < vertex_count; ++w)
    for (uint32_t i = adjacency.offset[w]; i < adjacency.offset[w + 1]; ++i)
      if (band[adjacency.neighbour[i]] == band[w]) pieces.join(uint32_t(w), adjacency.neighbour[i]);
  std::vector<uint32_t> label(vertex_count);
  for (size_t w = 0; w < vertex_count; ++w) label[w] = pieces.find(uint32_t(w));

  // Small pieces join the neighbouring piece they share the most edges with, smallest first (ties: the lowest id, a
  // piece's id being its label, the lowest vertex it started from); each join changes the sizes, and the smallest is
  // then found again. A piece without neighbours (a small component of its own) is left to merge_clusters: no join
  // can reach it (the adjacency is symmetric).
  const size_t min_size =
      std::max(size_t(settings.min_cluster_size), size_t(std::ceil(settings.min_cluster_share * double(vertex_count))));
  std::vector<size_t> size(vertex_count, 0);
  std::vector<std::vector<uint32_t>> members(vertex_count);
  for (size_t w = 0; w < vertex_count; ++w) ++size[label[w]], members[label[w]].push_back(uint32_t(w));
  std::set<std::pair<size_t, uint32_t>> small;  // (size, id) of the small pieces not yet joined or passed over
  for (size_t w = 0; w < vertex_count; ++w)
    if (label[w] == w && size[w] < min_size) small.insert({size[w], uint32_t(w)});
  std::vector<std::pair<uint32_t, size_t>> shared;  // neighbouring piece, shared edges
  while (!small.empty()) {
    const uint32_t piece = small.begin()->second;
    small.erase(small.begin());
    shared.clear();
    for (uint32_t w : members[piece])
      for (uint32_t i = adjacency.offset[w]; i < adjacency.offset[w + 1]; ++i) {
        const uint32_t other = label[adjacency.neighbour[i]];
        if (other == piece) continue;
        auto it = std::find_if(shared.begin(), shared.end(), [&](const auto& s) { return s.first == other; });
        if (it == shared.end())
          shared.push_back({other, 1});
        else
          ++it->second;
      }
    if (shared.empty()) continue;
    const uint32_t into = std::max_element(shared.begin(), shared.end(), [](const auto& a, const auto& b) {
                            return a.second != b.second ? a.second < b.second : a.first > b.first;
                          })->first;
    for (uint32_t w : members[piece]) label[w] = into;
    small.erase({size[into], into});
    size[into] += size[piece];
    members[into].insert(members[into].end(), members[piece].begin(), members[piece].end());
    members[piece] = std::vector<uint32_t>();
    if (size[into] < min_size) small.insert({size[into], into});
  }
  return compact(label);
}

Clusters morse_segmentation(const std::vector<double>& mu, const WeldedTopology& topology,
                            const VertexAdjacency& adjacency, const MorseSettings& settings, MorseBands* bands_out) {
  const size_t vertex_count = topology.welded_count();
  assert(mu.size() == vertex_count);
  std::vector<std::vector<uint32_t>> members(topology.component_count);
  for (size_t w = 0; w < vertex_count; ++w) members[topology.component[w]].push_back(uint32_t(w));

  MorseBands bands;
  bands.levels.resize(topology.component_count);
  std::vector<uint32_t> band(vertex_count);
  UnionFind pieces(vertex_count);
  for (size_t c = 0; c < topology.component_count; ++c) {
    const std::vector<uint32_t>& vertices = members[c];
    std::vector<double> sorted;
    for (uint32_t v : vertices) sorted.push_back(mu[v]);
    std::sort(sorted.begin(), sorted.end());
    // Initial cuts at equal shares of the component's vertices.
    std::vector<double>& levels = bands.levels[c];
    const size_t intervals = std::min(size_t(std::max(settings.intervals, 1)), vertices.size());
    for (size_t j = 1; j < intervals; ++j) levels.push_back(sorted[j * sorted.size() / intervals]);
    levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
    if (!levels.empty() && levels.front() <= sorted.front()) levels.erase(levels.begin());

    // Merge neighbouring intervals whose bands have as many pieces, until every neighbour differs.
    for (bool merged = true; merged && !levels.empty();) {
      merged = false;
      const std::vector<size_t> count = pieces_per_band(vertices, mu, adjacency, levels, band, pieces);
      std::vector<double> kept;
      for (size_t j = 0; j < levels.size(); ++j) {
        if (count[j] == count[j + 1])
          merged = true;  // the level between bands j and j+1 goes
        else
          kept.push_back(levels[j]);
      }
      levels.swap(kept);
    }
  }
  if (bands_out) *bands_out = bands;
  return clusters_from_levels(mu, topology, adjacency, bands, settings);
}

// The state of the merges so far: each cluster's statistics (of the merged set it stands for while alive), which
// alive clusters touch, the cost of merging each alive pair, and the merges made, in order.
struct ClusterMerges::Merging {
  const float* base;
  const Trajectories& frames;
  const VertexAdjacency& adjacency;
  std::mutex mutex;
  bool started = false;
  size_t count = 0;  // alive clusters
  std::vector<FitStatistics> statistics;
  std::vector<double> residual;
  std::vector<std::vector<bool>> touching;
  std::vector<bool> alive;
  std::vector<std::vector<double>> cost;
  std::vector<std::pair<uint32_t, uint32_t>> merges;  // (a, b): b merged into a

  Merging(const float* base_, const Trajectories& frames_, const VertexAdjacency& adjacency_)
      : base(base_), frames(frames_), adjacency(adjacency_) {}

  bool isolated(size_t a) const {
    return std::none_of(touching[a].begin(), touching[a].end(), [](bool t) { return t; });
  }
  // Cost of merging a and b (the increase of the residual); NaN where they may not merge.
  double merge_cost(size_t a, size_t b) const {
    if (!touching[a][b] && !isolated(a) && !isolated(b)) return NAN;
    FitStatistics merged = statistics[a];
    merged.add(statistics[b]);
    return merged.residual() - residual[a] - residual[b];
  }

  void start(const Clusters& clusters) {
    count = clusters.count;
    const size_t vertex_count = frames.vertex_count, frame_count = frames.frame_count;
    double origin[3] = {0, 0, 0};
    for (size_t v = 0; v < vertex_count; ++v)
      for (int c = 0; c < 3; ++c) origin[c] += base[v * 3 + size_t(c)] / double(vertex_count);
    statistics.resize(clusters.count);
    for (FitStatistics& s : statistics) {
      s.moments.assign(frame_count, Eigen::Matrix<double, 4, 3>::Zero());
      s.energy.assign(frame_count, 0.0);
    }
    for (size_t v = 0; v < vertex_count; ++v) {
      FitStatistics& s = statistics[clusters.label[v]];
      const Eigen::Vector4d x(base[v * 3] - origin[0], base[v * 3 + 1] - origin[1], base[v * 3 + 2] - origin[2], 1.0);
      s.gram += x * x.transpose();
      ++s.size;
      for (size_t f = 0; f < frame_count; ++f) {
        const float* p = frames.frame(f) + v * 3;
        const Eigen::RowVector3d y(p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]);
        s.moments[f] += x * y;
        s.energy[f] += y.squaredNorm();
      }
    }
    residual.resize(clusters.count);
    for (size_t k = 0; k < clusters.count; ++k) residual[k] = statistics[k].residual();

    // Candidate pairs: clusters that share an edge; clusters that share none with anyone (small separate
    // components) may join any cluster.
    touching.assign(clusters.count, std::vector<bool>(clusters.count, false));
    for (size_t v = 0; v < vertex_count; ++v)
      for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) {
        const uint32_t a = clusters.label[v], b = clusters.label[adjacency.neighbour[i]];
        if (a != b) touching[a][b] = touching[b][a] = true;
      }
    alive.assign(clusters.count, true);
    cost.assign(clusters.count, std::vector<double>(clusters.count, NAN));
    for (size_t a = 0; a < clusters.count; ++a)
      for (size_t b = a + 1; b < clusters.count; ++b) cost[a][b] = merge_cost(a, b);
    started = true;  // last: an allocation that failed above leaves it to be started again
  }

  // Merges while more than `target` clusters are alive and some pair may merge.
  void merge_down_to(size_t target) {
    const size_t n = statistics.size();
    for (; count > target; --count) {
      double best_cost = INFINITY;
      size_t best_a = 0, best_b = 0;
      for (size_t a = 0; a < n; ++a)
        for (size_t b = a + 1; b < n && alive[a]; ++b)
          if (alive[b] && cost[a][b] < best_cost) best_cost = cost[a][b], best_a = a, best_b = b;
      if (!std::isfinite(best_cost)) break;
      statistics[best_a].add(statistics[best_b]);
      residual[best_a] = statistics[best_a].residual();
      alive[best_b] = false;
      merges.emplace_back(uint32_t(best_a), uint32_t(best_b));
      for (size_t k = 0; k < n; ++k) {
        touching[best_a][k] = touching[best_a][k] || touching[best_b][k];
        touching[k][best_a] = touching[best_a][k];
        touching[best_b][k] = touching[k][best_b] = false;
      }
      touching[best_a][best_a] = false;
      for (size_t k = 0; k < n; ++k)
        if (alive[k] && k != best_a) {
          const size_t a = std::min(k, best_a), b = std::max(k, best_a);
          cost[a][b] = merge_cost(a, b);
        }
    }
  }
};

ClusterMerges::ClusterMerges(const Clusters& clusters, const float* base, const Trajectories& frames,
                             const VertexAdjacency& adjacency)
    : clusters_(clusters), merging_(std::make_unique<Merging>(base, frames, adjacency)) {}

ClusterMerges::~ClusterMerges() = default;

Clusters ClusterMerges::at(size_t target) const {
  if (clusters_.count <= std::max<size_t>(target, 1)) return clusters_;
  std::vector<uint32_t> into(clusters_.count);
  std::iota(into.begin(), into.end(), 0u);
  {
    const std::lock_guard<std::mutex> lock(merging_->mutex);
    if (!merging_->started) merging_->start(clusters_);
    merging_->merge_down_to(target);
    // The merges down to `target`: those made first (the merges stop early when no pair may merge).
    const size_t made = std::min(merging_->merges.size(), clusters_.count - target);
    for (size_t i = 0; i < made; ++i) into[merging_->merges[i].second] = merging_->merges[i].first;
  }
  std::vector<uint32_t> label(clusters_.label.size());
  for (size_t v = 0; v < label.size(); ++v) {
    uint32_t k = clusters_.label[v];
    while (into[k] != k) k = into[k];
    label[v] = k;
  }
  return compact(label);
}

Clusters merge_clusters(const Clusters& clusters, size_t target, const float* base, const Trajectories& frames,
                        const VertexAdjacency& adjacency) {
  return ClusterMerges(clusters, base, frames, adjacency).at(target);
}

}  // namespace segmorph
