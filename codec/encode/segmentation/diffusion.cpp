#include "encode/segmentation/diffusion.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "encode/segmentation/eigensolver.h"
#include "encode/segmentation/feature_points.h"
#include "encode/segmentation/laplacian.h"

namespace segmorph {
namespace {

double edge_length(const std::vector<double>& positions, uint32_t a, uint32_t b) {
  const double dx = positions[a * 3] - positions[b * 3], dy = positions[a * 3 + 1] - positions[b * 3 + 1],
               dz = positions[a * 3 + 2] - positions[b * 3 + 2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace

std::vector<double> edge_path_distances(const std::vector<double>& positions, const VertexAdjacency& adjacency,
                                        uint32_t source, double limit) {
  GeodesicBall ball(positions, adjacency);
  ball.reach(source, limit);
  return std::move(ball).distances();
}

GeodesicBall::GeodesicBall(const std::vector<double>& positions, const VertexAdjacency& adjacency)
    : positions_(positions), adjacency_(adjacency), distance_(adjacency.offset.size() - 1, INFINITY) {}

// Dijkstra's search over the edges, ended at `limit` (or at the first vertex `stop` accepts).
const std::vector<uint32_t>& GeodesicBall::reach(uint32_t source, double limit,
                                                 const std::function<bool(uint32_t)>& stop) {
  for (uint32_t v : reached_) distance_[v] = INFINITY;
  reached_.assign(1, source);
  stopped_ = stop && stop(source);
  if (stopped_) {
    distance_[source] = 0;
    return reached_;
  }
  using Entry = std::pair<double, uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
  distance_[source] = 0;
  queue.push({0, source});
  while (!queue.empty()) {
    const auto [d, u] = queue.top();
    queue.pop();
    if (d > distance_[u]) continue;
    for (uint32_t i = adjacency_.offset[u]; i < adjacency_.offset[u + 1]; ++i) {
      const uint32_t w = adjacency_.neighbour[i];
      const double candidate = d + edge_length(positions_, u, w);
      if (candidate < distance_[w] && candidate <= limit) {
        const bool first = distance_[w] == INFINITY;
        distance_[w] = candidate;
        if (first) {
          reached_.push_back(w);
          if (stop && stop(w)) {
            stopped_ = true;
            return reached_;
          }
        }
        queue.push({candidate, w});
      }
    }
  }
  return reached_;
}

Status diffusion_morse_function(const std::vector<double>& positions, const WeldedTopology& topology,
                                const VertexAdjacency& adjacency, const DiffusionSettings& settings,
                                MorseFunction& out) {
  const size_t vertex_count = topology.welded_count();
  out = MorseFunction();
  out.mu.assign(vertex_count, 0.0);
  CotangentLaplacian laplacian;
  SEGMORPH_RETURN_IF_ERROR(cotangent_laplacian(positions, topology.triangles, laplacian));
  ComponentSpectra spectra;
  EigenSettings eigen_settings;
  eigen_settings.progress = settings.progress;
  eigen_settings.threads = settings.threads;
  SEGMORPH_RETURN_IF_ERROR(component_spectra(laplacian, topology, settings.eigenpairs, spectra, eigen_settings));
  if (settings.progress) settings.progress("feature points and the Morse function");

  for (const ComponentSpectrum& component : spectra.components) {
    const std::vector<uint32_t>& vertices = component.vertices;
    const Eigen::VectorXd& lambda = component.eigenpairs.values;
    const Eigen::MatrixXd& phi = component.eigenpairs.vectors;
    const Eigen::Index pairs = lambda.size();
    double area = 0;
    for (uint32_t v : vertices) area += laplacian.mass[v];

    const auto [v1, v2] = farthest_points(positions, adjacency, vertices);
    out.farthest_points.push_back({v1, v2});
    if (pairs < 2 || !(lambda(1) > 0)) continue;  // a single vertex, or no surface: μ stays 0

    // Weights w_i = ∫ e^(−λ_i t) d(log t) over [t1, t2], trapezoid rule on log-spaced times.
    const double t2 = 1.0 / (2.0 * lambda(1)), t1 = std::min(t2, 4.0 / lambda(pairs - 1));
    const int samples = std::max(settings.time_samples, 2);
    const double step = (std::log(t2) - std::log(std::min(t1, t2))) / (samples - 1);
    Eigen::VectorXd weight = Eigen::VectorXd::Zero(pairs);
    for (int s = 0; s < samples; ++s) {
      const double t = std::exp(std::log(std::min(t1, t2)) + s * step);
      const double trapezoid = (s == 0 || s == samples - 1) ? 0.5 : 1.0;
      for (Eigen::Index i = 1; i < pairs; ++i) weight(i) += trapezoid * step * std::exp(-lambda(i) * t);
    }
    if (step == 0) weight.setOnes();
    weight(0) = 0;  // the constant eigenvector carries no distance

    // Integrated diffusion distance from local vertex p to every vertex of the component.
    auto distance_from = [&](Eigen::Index p) {
      Eigen::VectorXd d(Eigen::Index(vertices.size()));
      for (Eigen::Index v = 0; v < d.size(); ++v) {
        double sum = 0;
        for (Eigen::Index i = 1; i < pairs; ++i) {
          const double difference = phi(v, i) - phi(p, i);
          sum += weight(i) * difference * difference;
        }
        d(v) = sum;
      }
      return d;
    };
    std::vector<double> f1(vertex_count, 0.0), f2(vertex_count, 0.0);
    const Eigen::VectorXd d1 = distance_from(spectra.local_index[v1]), d2 = distance_from(spectra.local_index[v2]);
    for (size_t i = 0; i < vertices.size(); ++i) {
      f1[vertices[i]] = d1(Eigen::Index(i));
      f2[vertices[i]] = d2(Eigen::Index(i));
    }
    const std::vector<uint32_t> features =
        feature_points(f1, f2, vertices, positions, adjacency, settings.epsilon * std::sqrt(area), {v1, v2});

    for (uint32_t p : features) {
      out.feature_points.push_back(p);
      const Eigen::VectorXd d = distance_from(spectra.local_index[p]);
      const double share = laplacian.mass[p] / area;
      for (size_t i = 0; i < vertices.size(); ++i) out.mu[vertices[i]] += share * d(Eigen::Index(i));
    }
  }
  return Status::Ok();
}

}  // namespace segmorph
