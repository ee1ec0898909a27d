#include "encode/motion.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/parallel.h"
#include "encode/metrics.h"

namespace segmorph {
namespace {

// Applies the centred affine transform [L | t] (row-major 3 × 4) of a cluster with centroid c to x.
inline void apply(const double* transform, const double* c, const float* x, double* y) {
  const double d[3] = {x[0] - c[0], x[1] - c[1], x[2] - c[2]};
  for (int r = 0; r < 3; ++r)
    y[r] = transform[r * 4] * d[0] + transform[r * 4 + 1] * d[1] + transform[r * 4 + 2] * d[2] + transform[r * 4 + 3];
}

constexpr uint32_t kFitted = UINT32_MAX;

// fit_affine_motion, with each cluster k whose `source[k]` is not kFitted taking over cluster source[k]'s transforms
// of `previous` instead of being fitted.
AffineMotion fit_clusters(const float* base, const Trajectories& frames, const Clusters& clusters, size_t threads,
                          const std::vector<uint32_t>& source, const AffineMotion* previous) {
  const size_t vertex_count = frames.vertex_count, cluster_count = clusters.count;
  assert(clusters.label.size() == vertex_count);
  AffineMotion motion;
  motion.cluster_count = cluster_count;
  motion.frame_count = frames.frame_count;
  motion.centroid = cluster_centroids(base, clusters);
  motion.transforms.assign(frames.frame_count * cluster_count * 12, 0.0);

  // With base positions centred on their cluster's centroid, the least-squares affine map splits: t is the
  // mean of the frame positions and L = B G⁻¹, G = Σ x xᵀ (3 × 3), B = Σ (y − ȳ) xᵀ. A flat or tiny cluster
  // makes G (nearly) singular and L wild along the missing direction, so L is regularized towards the
  // cluster's best rotation R (Kabsch): L = (B + ρR)(G + ρI)⁻¹, ρ = 1e-6 of trace G. Where the cluster
  // spans all directions this moves L by about 1e-6 of its non-rigid part; where it is flat, the missing
  // direction moves rigidly. The floor of ρ, 1e-30 squared model units, is for a cluster of one vertex (G = 0):
  // the 3 × 3 inverse divides by det(G + ρI) = ρ³, which must not underflow to 0 (with 1e-300 it did, and the
  // cluster's motion came out NaN).
  std::vector<Eigen::Matrix3d> gram(cluster_count, Eigen::Matrix3d::Zero());
  std::vector<size_t> size(cluster_count, 0);
  std::vector<Eigen::Vector3d> centred(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) {
    const uint32_t k = clusters.label[v];
    const double* c = &motion.centroid[k * 3];
    centred[v] = Eigen::Vector3d(base[v * 3] - c[0], base[v * 3 + 1] - c[1], base[v * 3 + 2] - c[2]);
    gram[k] += centred[v] * centred[v].transpose();
    ++size[k];
  }
  std::vector<double> rho(cluster_count);
  std::vector<Eigen::Matrix3d> inverse(cluster_count);
  for (size_t k = 0; k < cluster_count; ++k) {
    rho[k] = 1e-6 * gram[k].trace() + 1e-30;
    inverse[k] = (gram[k] + rho[k] * Eigen::Matrix3d::Identity()).inverse();
  }

  // B = Σ (y − ȳ) xᵀ = Σ y xᵀ − ȳ (Σ x)ᵀ: one pass over the frame's vertices for both sums (Σ x is 0 but for
  // rounding, kept so that B does not depend on where the frame sits).
  std::vector<Eigen::Vector3d> centred_sum(cluster_count, Eigen::Vector3d::Zero());
  for (size_t v = 0; v < vertex_count; ++v) centred_sum[clusters.label[v]] += centred[v];
  // Each cluster's vertices in ascending order (member_offset[k] to member_offset[k + 1] of `members`): a cluster's
  // sums are taken in registers, in the order a pass over every vertex would add them.
  std::vector<uint32_t> member_offset(cluster_count + 1, 0), members(vertex_count);
  for (size_t v = 0; v < vertex_count; ++v) ++member_offset[clusters.label[v] + 1];
  for (size_t k = 0; k < cluster_count; ++k) member_offset[k + 1] += member_offset[k];
  {
    std::vector<uint32_t> next(member_offset.begin(), member_offset.end() - 1);
    for (size_t v = 0; v < vertex_count; ++v) members[next[clusters.label[v]]++] = uint32_t(v);
  }
  // Each frame's fit is its own: the frames are split over threads.
  parallel_ranges(frames.frame_count, thread_count(threads), [&](size_t begin, size_t end) {
    std::vector<Eigen::Matrix3d> moments(cluster_count);
    std::vector<Eigen::Vector3d> mean(cluster_count);
    for (size_t f = begin; f < end; ++f) {
      const float* frame = frames.frame(f);
      for (size_t k = 0; k < cluster_count; ++k) {
        if (source[k] != kFitted) continue;
        // Σ y and Σ y xᵀ in scalars, which stay in registers (an Eigen matrix here did not).
        double s0 = 0, s1 = 0, s2 = 0, m00 = 0, m01 = 0, m02 = 0, m10 = 0, m11 = 0, m12 = 0, m20 = 0, m21 = 0, m22 = 0;
        for (uint32_t i = member_offset[k]; i < member_offset[k + 1]; ++i) {
          const size_t v = members[i];
          const double y0 = frame[v * 3], y1 = frame[v * 3 + 1], y2 = frame[v * 3 + 2];
          const double x0 = centred[v](0), x1 = centred[v](1), x2 = centred[v](2);
          s0 += y0, s1 += y1, s2 += y2;
          m00 += y0 * x0, m01 += y0 * x1, m02 += y0 * x2;
          m10 += y1 * x0, m11 += y1 * x1, m12 += y1 * x2;
          m20 += y2 * x0, m21 += y2 * x1, m22 += y2 * x2;
        }
        Eigen::Matrix3d moment;
        moment << m00, m01, m02, m10, m11, m12, m20, m21, m22;
        mean[k] = Eigen::Vector3d(s0, s1, s2) / double(std::max<size_t>(size[k], 1));
        moments[k] = moment - mean[k] * centred_sum[k].transpose();
      }
      for (size_t k = 0; k < cluster_count; ++k) {
        double* transform = motion.transform(f, k);
        if (source[k] != kFitted) {
          const double* taken = previous->transform(f, source[k]);
          std::copy(taken, taken + 12, transform);
          continue;
        }
        Eigen::JacobiSVD<Eigen::Matrix3d> svd(moments[k], Eigen::ComputeFullU | Eigen::ComputeFullV);
        Eigen::Matrix3d rotation = svd.matrixU() * svd.matrixV().transpose();
        if (rotation.determinant() < 0) {
          Eigen::Matrix3d u = svd.matrixU();
          u.col(2) *= -1;
          rotation = u * svd.matrixV().transpose();
        }
        const Eigen::Matrix3d linear = (moments[k] + rho[k] * rotation) * inverse[k];
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) transform[r * 4 + c] = linear(r, c);
          transform[r * 4 + 3] = mean[k](r);
        }
      }
    }
  });
  return motion;
}

}  // namespace

AffineMotion fit_affine_motion(const float* base, const Trajectories& frames, const Clusters& clusters,
                               size_t threads) {
  return fit_clusters(base, frames, clusters, threads, std::vector<uint32_t>(clusters.count, kFitted), nullptr);
}

AffineMotion refit_affine_motion(const float* base, const Trajectories& frames, const Clusters& clusters,
                                 const Clusters& previous_clusters, const AffineMotion& previous, size_t threads) {
  assert(previous_clusters.label.size() == clusters.label.size());
  assert(previous.cluster_count == previous_clusters.count && previous.frame_count == frames.frame_count);
  // Cluster k has the vertices of previous cluster j when all of them were in j and j had as many.
  std::vector<uint32_t> source(clusters.count, kFitted);
  std::vector<char> one_source(clusters.count, 1);
  std::vector<size_t> size(clusters.count, 0), previous_size(previous_clusters.count, 0);
  for (size_t v = 0; v < clusters.label.size(); ++v) {
    const uint32_t k = clusters.label[v], j = previous_clusters.label[v];
    if (source[k] == kFitted)
      source[k] = j;
    else if (source[k] != j)
      one_source[k] = 0;
    ++size[k], ++previous_size[j];
  }
  for (size_t k = 0; k < clusters.count; ++k)
    if (source[k] != kFitted && (!one_source[k] || previous_size[source[k]] != size[k])) source[k] = kFitted;
  return fit_clusters(base, frames, clusters, threads, source, &previous);
}

double motion_compensation_error(const float* base, const Trajectories& frames, const Clusters& clusters,
                                 const AffineMotion& motion) {
  double sum = 0;
  for (size_t f = 0; f < frames.frame_count; ++f) {
    const float* frame = frames.frame(f);
    for (size_t v = 0; v < frames.vertex_count; ++v) {
      const uint32_t k = clusters.label[v];
      double y[3];
      apply(motion.transform(f, k), &motion.centroid[k * 3], base + v * 3, y);
      for (int c = 0; c < 3; ++c) sum += (y[c] - frame[v * 3 + size_t(c)]) * (y[c] - frame[v * 3 + size_t(c)]);
    }
  }
  const double diagonal_squared = bounding_box_diagonal_squared(base, frames.vertex_count);
  const double count = double(frames.vertex_count) * double(frames.frame_count);
  return count > 0 && diagonal_squared > 0 ? sum / (count * diagonal_squared) : 0.0;
}

ClusterWeights own_cluster_weights(const Clusters& clusters) {
  ClusterWeights weights;
  weights.offset.resize(clusters.label.size() + 1);
  for (size_t v = 0; v <= clusters.label.size(); ++v) weights.offset[v] = uint32_t(v);
  weights.cluster = clusters.label;
  weights.weight.assign(clusters.label.size(), 1.0);
  return weights;
}

namespace {

// fit_cluster_weights for the vertices [begin, end): their offsets from 0.
ClusterWeights fit_range_weights(const float* base, const Trajectories& frames, const Clusters& clusters,
                                 const AffineMotion& motion, const std::vector<uint32_t>& adjacency_offset,
                                 const std::vector<uint32_t>& adjacency, int rings, int max_clusters, size_t begin,
                                 size_t end) {
  const size_t vertex_count = frames.vertex_count, frame_count = frames.frame_count;
  ClusterWeights weights;
  weights.offset.assign(1, 0);
  std::vector<uint32_t> ring, next, seen_stamp(vertex_count, UINT32_MAX), candidates;
  std::vector<double> predictions;  // frame-major: F × m × 3
  for (size_t v = begin; v < end; ++v) {
    const uint32_t own = clusters.label[v];
    // Clusters within `rings` rings, own first.
    candidates.assign(1, own);
    ring.assign(1, uint32_t(v));
    seen_stamp[v] = uint32_t(v);
    for (int r = 0; r < rings; ++r) {
      next.clear();
      for (uint32_t u : ring)
        for (uint32_t i = adjacency_offset[u]; i < adjacency_offset[u + 1]; ++i) {
          const uint32_t w = adjacency[i];
          if (seen_stamp[w] == uint32_t(v)) continue;
          seen_stamp[w] = uint32_t(v);
          next.push_back(w);
          if (std::find(candidates.begin(), candidates.end(), clusters.label[w]) == candidates.end())
            candidates.push_back(clusters.label[w]);
        }
      ring.swap(next);
    }
    const size_t m_all = candidates.size();
    predictions.resize(frame_count * m_all * 3);
    for (size_t f = 0; f < frame_count; ++f)
      for (size_t j = 0; j < m_all; ++j)
        apply(motion.transform(f, candidates[j]), &motion.centroid[candidates[j] * 3], base + v * 3,
              &predictions[(f * m_all + j) * 3]);

    // Keep the own cluster and the candidates whose transforms alone fit the vertex best.
    std::vector<size_t> kept(m_all);
    for (size_t j = 0; j < m_all; ++j) kept[j] = j;
    if (int(m_all) > max_clusters) {
      std::vector<double> error(m_all, 0.0);
      for (size_t f = 0; f < frame_count; ++f)
        for (size_t j = 0; j < m_all; ++j)
          for (int c = 0; c < 3; ++c) {
            const double d = predictions[(f * m_all + j) * 3 + size_t(c)] - frames.frame(f)[v * 3 + size_t(c)];
            error[j] += d * d;
          }
      std::sort(kept.begin() + 1, kept.end(), [&](size_t a, size_t b) { return error[a] < error[b]; });
      kept.resize(size_t(max_clusters));
    }
    const size_t m = kept.size();
    if (m == 1) {
      weights.cluster.push_back(own);
      weights.weight.push_back(1.0);
      weights.offset.push_back(uint32_t(weights.cluster.size()));
      continue;
    }

    // min ‖P w − y‖² + ρ ‖w − e_own‖²  subject to Σ w = 1, solved through its KKT system. P's columns are the
    // candidates' predictions over all frames. ρ is 1e-4 of the mean squared difference between a candidate's
    // and the own cluster's predictions: negligible where the candidates differ, decisive where they do not.
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(Eigen::Index(m), Eigen::Index(m));
    Eigen::VectorXd right = Eigen::VectorXd::Zero(Eigen::Index(m));
    double spread = 0;
    for (size_t f = 0; f < frame_count; ++f) {
      const float* y = frames.frame(f) + v * 3;
      for (size_t a = 0; a < m; ++a) {
        const double* pa = &predictions[(f * m_all + kept[a]) * 3];
        for (size_t b = a; b < m; ++b) {
          const double* pb = &predictions[(f * m_all + kept[b]) * 3];
          normal(Eigen::Index(a), Eigen::Index(b)) += pa[0] * pb[0] + pa[1] * pb[1] + pa[2] * pb[2];
        }
        right(Eigen::Index(a)) += pa[0] * y[0] + pa[1] * y[1] + pa[2] * y[2];
        const double* po = &predictions[(f * m_all + kept[0]) * 3];
        spread +=
            (pa[0] - po[0]) * (pa[0] - po[0]) + (pa[1] - po[1]) * (pa[1] - po[1]) + (pa[2] - po[2]) * (pa[2] - po[2]);
      }
    }
    normal = normal.selfadjointView<Eigen::Upper>();
    const double rho = 1e-4 * spread / double(m - 1) + 1e-300;
    Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(Eigen::Index(m + 1), Eigen::Index(m + 1));
    kkt.topLeftCorner(Eigen::Index(m), Eigen::Index(m)) =
        normal + rho * Eigen::MatrixXd::Identity(Eigen::Index(m), Eigen::Index(m));
    kkt.block(0, Eigen::Index(m), Eigen::Index(m), 1).setOnes();
    kkt.block(Eigen::Index(m), 0, 1, Eigen::Index(m)).setOnes();
    Eigen::VectorXd rhs(Eigen::Index(m + 1));
    rhs.head(Eigen::Index(m)) = right;
    rhs(0) += rho;
    rhs(Eigen::Index(m)) = 1.0;
    const Eigen::VectorXd solution = kkt.fullPivLu().solve(rhs);
    bool finite = solution.allFinite();
    for (size_t a = 0; a < m && finite; ++a) {
      weights.cluster.push_back(candidates[kept[a]]);
      weights.weight.push_back(solution(Eigen::Index(a)));
    }
    if (!finite) {  // cannot happen with ρ > 0; kept as a guard against NaN input
      weights.cluster.resize(weights.offset.back());
      weights.weight.resize(weights.offset.back());
      weights.cluster.push_back(own);
      weights.weight.push_back(1.0);
    }
    weights.offset.push_back(uint32_t(weights.cluster.size()));
  }
  return weights;
}

}  // namespace

// Every vertex's weights depend on it alone: the vertices split into ranges (more than threads, for balance: a
// vertex's cost grows with its candidates), fitted on threads and joined in vertex order.
ClusterWeights fit_cluster_weights(const float* base, const Trajectories& frames, const Clusters& clusters,
                                   const AffineMotion& motion, const std::vector<uint32_t>& adjacency_offset,
                                   const std::vector<uint32_t>& adjacency, int rings, int max_clusters,
                                   size_t threads) {
  const size_t vertex_count = frames.vertex_count;
  const size_t ranges = std::min(vertex_count, 4 * thread_count(threads));
  std::vector<ClusterWeights> parts(ranges);
  parallel_items(ranges, thread_count(threads), [&](size_t r) {
    parts[r] = fit_range_weights(base, frames, clusters, motion, adjacency_offset, adjacency, rings, max_clusters,
                                 vertex_count * r / ranges, vertex_count * (r + 1) / ranges);
  });
  ClusterWeights weights;
  weights.offset.assign(1, 0);
  for (const ClusterWeights& part : parts) {
    const uint32_t first = weights.offset.back();
    for (size_t i = 1; i < part.offset.size(); ++i) weights.offset.push_back(first + part.offset[i]);
    weights.cluster.insert(weights.cluster.end(), part.cluster.begin(), part.cluster.end());
    weights.weight.insert(weights.weight.end(), part.weight.begin(), part.weight.end());
  }
  return weights;
}

}  // namespace segmorph
