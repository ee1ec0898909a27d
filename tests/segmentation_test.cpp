#include "encode/segmentation/segmentation.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include "test_meshes.h"

namespace segmorph {
namespace {

using testing::height_field;

// An n × n grid of unit squares (two triangles each) in the plane z = 0, with the squares whose lower-left
// corner (i, j) satisfies `hole` left out. Returns the welded topology, adjacency and base positions.
struct Grid {
  WeldedTopology topology;
  VertexAdjacency adjacency;
  std::vector<float> base;
};

template <typename Hole>
Grid make_grid(int n, Hole hole) {
  const FrameSequence clip = height_field(n, [](int, int) { return 0.0; }, hole);
  Grid grid;
  grid.topology = weld_topology({clip});
  grid.adjacency = vertex_adjacency(grid.topology);
  grid.base = clip.positions;
  return grid;
}

TEST(Segmentation, BandsOfAStripMergeIntoOneCluster) {
  const Grid grid = make_grid(20, [](int, int) { return false; });
  std::vector<double> mu;
  for (size_t v = 0; v < grid.topology.welded_count(); ++v) mu.push_back(grid.base[v * 3]);  // μ = x
  MorseBands bands;
  const Clusters clusters = morse_segmentation(mu, grid.topology, grid.adjacency, MorseSettings(), &bands);
  EXPECT_EQ(clusters.count, 1u);
  ASSERT_EQ(bands.levels.size(), 1u);
  EXPECT_TRUE(bands.levels[0].empty());
}

TEST(Segmentation, AHoleSplitsTheBandsItCrosses) {
  // A 30 × 30 grid with a slit (the squares over x in [10, 20), y in [10, 11) left out, so no vertex is left
  // without triangles): with μ = x, bands left of the slit are one piece, bands across it two (below and
  // above), bands right of it one: four clusters.
  const Grid grid = make_grid(30, [](int i, int j) { return i >= 10 && i < 20 && j == 10; });
  std::vector<double> mu;
  for (size_t v = 0; v < grid.topology.welded_count(); ++v) mu.push_back(grid.base[v * 3]);
  MorseSettings settings;
  settings.intervals = 30;
  const Clusters clusters = morse_segmentation(mu, grid.topology, grid.adjacency, settings);
  EXPECT_EQ(clusters.count, 4u);
  // The corners (0,0) and (30,30) are in different clusters; (15,0) and (15,30) too.
  auto at = [&](int i, int j) { return clusters.label[size_t(j * 31 + i)]; };
  EXPECT_NE(at(0, 0), at(30, 30));
  EXPECT_NE(at(15, 0), at(15, 30));
  EXPECT_EQ(at(0, 0), at(0, 30));
  std::set<uint32_t> distinct(clusters.label.begin(), clusters.label.end());
  EXPECT_EQ(distinct.size(), clusters.count);
}

// clusters_from_levels as first written (the smallest piece found again by a pass over every vertex after each
// join), the reference for the faster one.
Clusters pieces_joined_by_passes(const std::vector<double>& mu, const WeldedTopology& topology,
                                 const VertexAdjacency& adjacency, const MorseBands& bands, size_t min_size) {
  const size_t count = topology.welded_count();
  std::vector<uint32_t> band(count), label(count);
  for (size_t w = 0; w < count; ++w) {
    const std::vector<double>& levels = bands.levels[topology.component[w]];
    band[w] = uint32_t(std::upper_bound(levels.begin(), levels.end(), mu[w]) - levels.begin());
  }
  // Each piece labelled by its lowest vertex: a search from every vertex not yet labelled, in order.
  std::vector<char> seen(count, 0);
  for (size_t w = 0; w < count; ++w) {
    if (seen[w]) continue;
    std::vector<uint32_t> stack = {uint32_t(w)};
    seen[w] = 1;
    while (!stack.empty()) {
      const uint32_t v = stack.back();
      stack.pop_back();
      label[v] = uint32_t(w);
      for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) {
        const uint32_t u = adjacency.neighbour[i];
        if (!seen[u] && band[u] == band[v]) seen[u] = 1, stack.push_back(u);
      }
    }
  }
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<size_t> size(count, 0);
    for (size_t w = 0; w < count; ++w) ++size[label[w]];
    std::vector<uint32_t> order;
    for (size_t w = 0; w < count; ++w)
      if (label[w] == w && size[w] < min_size) order.push_back(uint32_t(w));
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return size[a] != size[b] ? size[a] < size[b] : a < b; });
    for (uint32_t piece : order) {
      std::map<uint32_t, size_t> shared;
      for (size_t w = 0; w < count; ++w)
        if (label[w] == piece)
          for (uint32_t i = adjacency.offset[w]; i < adjacency.offset[w + 1]; ++i)
            if (label[adjacency.neighbour[i]] != piece) ++shared[label[adjacency.neighbour[i]]];
      if (shared.empty()) continue;
      uint32_t best = shared.begin()->first;
      for (const auto& [other, edges] : shared)
        if (edges > shared[best]) best = other;  // ties: the lowest id, met first
      for (size_t w = 0; w < count; ++w)
        if (label[w] == piece) label[w] = best;
      changed = true;
      break;
    }
  }
  return compact(label);
}

TEST(Segmentation, SmallPiecesJoinAsTheOneByOnePassesJoinThem) {
  // Grids with holes (some cut off corners and strips: components of their own, some tiny) and a rough μ cut at
  // many levels: many small pieces, joined in chains.
  for (unsigned seed = 1; seed <= 6; ++seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> unit(0, 1);
    std::vector<char> holes(40 * 40);
    for (char& hole : holes) hole = unit(random) < 0.12;
    const Grid grid = make_grid(40, [&](int i, int j) { return holes[size_t(j * 40 + i)] != 0; });
    const size_t count = grid.topology.welded_count();
    std::vector<double> mu(count);
    for (size_t w = 0; w < count; ++w)
      mu[w] = 0.05 * grid.base[w * 3] + std::sin(0.7 * grid.base[w * 3 + 1]) + 0.4 * unit(random);
    MorseBands bands;
    bands.levels.resize(grid.topology.component_count);
    for (std::vector<double>& levels : bands.levels) {
      for (int j = 0; j < 30; ++j) levels.push_back(-1.0 + 4.5 * unit(random));
      std::sort(levels.begin(), levels.end());
    }
    MorseSettings settings;
    settings.min_cluster_size = 5 + int(seed) * 4;
    settings.min_cluster_share = 0;
    const Clusters fast = clusters_from_levels(mu, grid.topology, grid.adjacency, bands, settings);
    const Clusters reference =
        pieces_joined_by_passes(mu, grid.topology, grid.adjacency, bands, size_t(settings.min_cluster_size));
    EXPECT_GT(grid.topology.component_count, 1u) << "seed " << seed;
    EXPECT_GT(reference.count, 10u) << "seed " << seed;
    EXPECT_EQ(fast.count, reference.count) << "seed " << seed;
    EXPECT_EQ(fast.label, reference.label) << "seed " << seed;
  }
}

TEST(Segmentation, MergeJoinsClustersThatMoveAlikeFirst) {
  // Four vertical strips of a grid; strips 0 and 1 translate together, strips 2 and 3 rotate differently.
  const Grid grid = make_grid(16, [](int, int) { return false; });
  const size_t vertex_count = grid.topology.welded_count();
  Clusters clusters;
  clusters.count = 4;
  for (size_t v = 0; v < vertex_count; ++v) clusters.label.push_back(uint32_t(std::min(3.0f, grid.base[v * 3] / 4.25f)));
  Trajectories frames;
  frames.vertex_count = vertex_count;
  frames.frame_count = 3;
  for (int f = 0; f < 3; ++f)
    for (size_t v = 0; v < vertex_count; ++v) {
      const float x = grid.base[v * 3], y = grid.base[v * 3 + 1];
      const uint32_t k = clusters.label[v];
      const float angle = k < 2 ? 0.0f : (k == 2 ? 0.2f : -0.3f) * float(f);
      frames.positions.insert(frames.positions.end(), {x * std::cos(angle) - y * std::sin(angle) + float(f),
                                                       x * std::sin(angle) + y * std::cos(angle), 0.0f});
    }
  const Clusters merged = merge_clusters(clusters, 3, grid.base.data(), frames, grid.adjacency);
  ASSERT_EQ(merged.count, 3u);
  auto strip = [&](int s) { return merged.label[size_t(s * 4 + 1)]; };  // a vertex of strip s on the first row
  EXPECT_EQ(strip(0), strip(1));
  EXPECT_NE(strip(1), strip(2));
  EXPECT_NE(strip(2), strip(3));
}

// merge_clusters as first written (a merge of its own for each target), the reference for the shared merges.
struct ReferenceStatistics {
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
  void add(const ReferenceStatistics& other) {
    gram += other.gram;
    for (size_t f = 0; f < moments.size(); ++f) {
      moments[f] += other.moments[f];
      energy[f] += other.energy[f];
    }
    size += other.size;
  }
};

Clusters merged_for_one_target(const Clusters& clusters, size_t target, const float* base, const Trajectories& frames,
                               const VertexAdjacency& adjacency) {
  if (clusters.count <= std::max<size_t>(target, 1)) return clusters;
  const size_t vertex_count = frames.vertex_count, frame_count = frames.frame_count;
  double origin[3] = {0, 0, 0};
  for (size_t v = 0; v < vertex_count; ++v)
    for (int c = 0; c < 3; ++c) origin[c] += base[v * 3 + size_t(c)] / double(vertex_count);

  std::vector<ReferenceStatistics> statistics(clusters.count);
  for (ReferenceStatistics& s : statistics) {
    s.moments.assign(frame_count, Eigen::Matrix<double, 4, 3>::Zero());
    s.energy.assign(frame_count, 0.0);
  }
  for (size_t v = 0; v < vertex_count; ++v) {
    ReferenceStatistics& s = statistics[clusters.label[v]];
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
  std::vector<double> residual(clusters.count);
  for (size_t k = 0; k < clusters.count; ++k) residual[k] = statistics[k].residual();

  // Candidate pairs: clusters that share an edge; clusters that share none with anyone (small separate
  // components) may join any cluster.
  std::vector<std::vector<bool>> touching(clusters.count, std::vector<bool>(clusters.count, false));
  for (size_t v = 0; v < vertex_count; ++v)
    for (uint32_t i = adjacency.offset[v]; i < adjacency.offset[v + 1]; ++i) {
      const uint32_t a = clusters.label[v], b = clusters.label[adjacency.neighbour[i]];
      if (a != b) touching[a][b] = touching[b][a] = true;
    }
  std::vector<bool> alive(clusters.count, true);
  std::vector<uint32_t> into(clusters.count);
  std::iota(into.begin(), into.end(), 0u);
  auto isolated = [&](size_t a) {
    return std::none_of(touching[a].begin(), touching[a].end(), [](bool t) { return t; });
  };
  // Cost of merging a and b (the increase of the residual), cached; NaN where they may not merge.
  auto merge_cost = [&](size_t a, size_t b) -> double {
    if (!touching[a][b] && !isolated(a) && !isolated(b)) return NAN;
    ReferenceStatistics merged = statistics[a];
    merged.add(statistics[b]);
    return merged.residual() - residual[a] - residual[b];
  };
  std::vector<std::vector<double>> cost(clusters.count, std::vector<double>(clusters.count, NAN));
  for (size_t a = 0; a < clusters.count; ++a)
    for (size_t b = a + 1; b < clusters.count; ++b) cost[a][b] = merge_cost(a, b);

  for (size_t count = clusters.count; count > target; --count) {
    double best_cost = INFINITY;
    size_t best_a = 0, best_b = 0;
    for (size_t a = 0; a < clusters.count; ++a)
      for (size_t b = a + 1; b < clusters.count && alive[a]; ++b)
        if (alive[b] && cost[a][b] < best_cost) best_cost = cost[a][b], best_a = a, best_b = b;
    if (!std::isfinite(best_cost)) break;
    statistics[best_a].add(statistics[best_b]);
    residual[best_a] = statistics[best_a].residual();
    alive[best_b] = false;
    into[best_b] = uint32_t(best_a);
    for (size_t k = 0; k < clusters.count; ++k) {
      touching[best_a][k] = touching[best_a][k] || touching[best_b][k];
      touching[k][best_a] = touching[best_a][k];
      touching[best_b][k] = touching[k][best_b] = false;
    }
    touching[best_a][best_a] = false;
    for (size_t k = 0; k < clusters.count; ++k)
      if (alive[k] && k != best_a) {
        const double c = merge_cost(std::min(k, best_a), std::max(k, best_a));
        cost[std::min(k, best_a)][std::max(k, best_a)] = c;
      }
  }
  std::vector<uint32_t> label(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    uint32_t k = clusters.label[v];
    while (into[k] != k) k = into[k];
    label[v] = k;
  }
  return compact(label);
}

TEST(Segmentation, SharedMergesGiveEachTargetWhatItsOwnMergeGives) {
  // Sixteen column strips of a grid, each turning by its own angle: a target asked after a smaller one (whose merges
  // went further) must get the clusters of the merges down to it only, from any thread; merge_clusters too.
  const Grid grid = make_grid(15, [](int, int) { return false; });
  const size_t vertex_count = grid.topology.welded_count();
  Clusters clusters;
  clusters.count = 16;
  for (size_t v = 0; v < vertex_count; ++v) clusters.label.push_back(uint32_t(grid.base[v * 3]));
  Trajectories frames;
  frames.vertex_count = vertex_count;
  frames.frame_count = 4;
  for (int f = 0; f < 4; ++f)
    for (size_t v = 0; v < vertex_count; ++v) {
      const float x = grid.base[v * 3], y = grid.base[v * 3 + 1];
      const uint32_t k = clusters.label[v];
      const float angle = 0.03f * float((k * 7) % 5) * float(f) + 0.01f * float(k % 3);
      frames.positions.insert(frames.positions.end(), {x * std::cos(angle) - y * std::sin(angle),
                                                       x * std::sin(angle) + y * std::cos(angle), 0.1f * float(k)});
    }
  const std::vector<size_t> targets = {9, 3, 12, 1, 5, 16, 20, 0, 7};
  std::vector<Clusters> alone;
  for (size_t target : targets)
    alone.push_back(merged_for_one_target(clusters, target, grid.base.data(), frames, grid.adjacency));
  EXPECT_EQ(alone[0].count, 9u);
  EXPECT_EQ(alone[1].count, 3u);
  EXPECT_EQ(alone[6].count, 16u);
  for (size_t i = 0; i < targets.size(); ++i)
    EXPECT_EQ(merge_clusters(clusters, targets[i], grid.base.data(), frames, grid.adjacency).label, alone[i].label);
  const ClusterMerges merges(clusters, grid.base.data(), frames, grid.adjacency);
  for (size_t i = 0; i < targets.size(); ++i) {
    const Clusters shared = merges.at(targets[i]);
    EXPECT_EQ(shared.count, alone[i].count) << "target " << targets[i];
    EXPECT_EQ(shared.label, alone[i].label) << "target " << targets[i];
  }
  // The same from threads, each asking for its own targets at once.
  const ClusterMerges threaded(clusters, grid.base.data(), frames, grid.adjacency);
  std::vector<Clusters> got(targets.size());
  std::vector<std::thread> threads;
  for (size_t t = 0; t < 3; ++t)
    threads.emplace_back([&, t] {
      for (size_t i = t; i < targets.size(); i += 3) got[i] = threaded.at(targets[i]);
    });
  for (std::thread& thread : threads) thread.join();
  for (size_t i = 0; i < targets.size(); ++i) EXPECT_EQ(got[i].label, alone[i].label) << "target " << targets[i];
}

}  // namespace
}  // namespace segmorph
