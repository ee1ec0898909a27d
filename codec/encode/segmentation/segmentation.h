// Morse segmentation (Hachani et al., §2.2): the range of a scalar function μ over the surface is cut into
// intervals; the band of vertices in each interval has some number of connected pieces; contiguous
// intervals with the same number merge, until neighbouring intervals differ. The clusters are the
// connected pieces of the final bands: by Morse theory, a change in the number of pieces marks a critical
// level of μ (a branching of the shape), so each band is a run of tubes between branchings.
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "common/topology.h"
#include "encode/motion.h"

namespace segmorph {

struct MorseSettings {
  int intervals = 24;  // initial intervals per connected component, each holding an equal share of its vertices
  double min_cluster_share = 0.004;  // pieces smaller than this share of the vertices (and than min_cluster_size)
  int min_cluster_size = 12;         //   join the neighbouring cluster they share most edges with
};

// Band boundaries of one segmentation: per mesh component, the μ levels that separate its final bands
// (ascending), kept so that refinement can move them.
struct MorseBands {
  std::vector<std::vector<double>> levels;  // per connected component
};

// Segments the welded mesh by μ (W values). Components of the mesh are segmented separately.
Clusters morse_segmentation(const std::vector<double>& mu, const WeldedTopology& topology,
                            const VertexAdjacency& adjacency, const MorseSettings& settings,
                            MorseBands* bands = nullptr);

// The clusters implied by band levels: per component, vertex w falls in band b when
// levels[b-1] <= μ(w) < levels[b]; clusters are the connected pieces of each band, small pieces merged.
Clusters clusters_from_levels(const std::vector<double>& mu, const WeldedTopology& topology,
                              const VertexAdjacency& adjacency, const MorseBands& bands, const MorseSettings& settings);

// Merges clusters along shared edges, smallest increase of the motion compensation error first, until
// `target` clusters remain (no-op when there are already that few).
Clusters merge_clusters(const Clusters& clusters, size_t target, const float* base, const Trajectories& frames,
                        const VertexAdjacency& adjacency);

// merge_clusters to any number of targets from the same clusters, sharing the work: the merges are made once, in
// order, as far as the smallest target asked so far (the merges down to a target are those down to any larger one,
// then more), and the frames are read once. `at(target)` is merge_clusters(clusters, target, ...), and may be called
// from several threads at once. The arguments must outlive the object.
class ClusterMerges {
 public:
  ClusterMerges(const Clusters& clusters, const float* base, const Trajectories& frames,
                const VertexAdjacency& adjacency);
  ~ClusterMerges();
  ClusterMerges(const ClusterMerges&) = delete;
  ClusterMerges& operator=(const ClusterMerges&) = delete;

  Clusters at(size_t target) const;

 private:
  struct Merging;
  const Clusters& clusters_;
  std::unique_ptr<Merging> merging_;
};

// Labels renumbered to 0..K−1 in order of first appearance: clusters no vertex has disappear. Labels must be below
// label.size().
Clusters compact(const std::vector<uint32_t>& label);

}  // namespace segmorph
