#include "glimpse/learning/classifiers.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

namespace glimpse {

// ---- Keypoint codebook ----------------------------------------------------------------------------

Eigen::MatrixXd descriptor_rows(const std::vector<Descriptor>& descriptors) {
  Eigen::MatrixXd rows(static_cast<Eigen::Index>(descriptors.size()), kDescriptorSize);
  for (size_t i = 0; i < descriptors.size(); ++i) rows.row(static_cast<Eigen::Index>(i)) = descriptors[i].cast<double>().transpose();
  return rows;
}

Expected<KeypointCodebook> fit_keypoint_codebook(const Eigen::MatrixXd& descriptors, const CodebookParams& params) {
  if (descriptors.rows() < params.clusters)
    return invalid_argument("a codebook of " + std::to_string(params.clusters) + " clusters needs at least as many keypoints; the training clouds gave " +
                            std::to_string(descriptors.rows()));
  KeypointCodebook cb;
  cb.standardiser = fit_standardiser(descriptors);
  const Eigen::MatrixXd z = standardise(cb.standardiser, descriptors);
  auto pca = fit_pca(z, params.explained_variance, -1, 1, params.threads);
  if (!pca.ok()) return pca.error();
  cb.pca = std::move(*pca);
  KMeansParams km;
  km.k = params.clusters;
  km.restarts = params.restarts;
  km.seed = params.seed;
  km.threads = params.threads;
  auto clusters = kmeans(project(cb.pca, z, params.threads), km);
  if (!clusters.ok()) return clusters.error();
  cb.centres = std::move(clusters->centres);
  return cb;
}

std::vector<int> keypoint_words(const KeypointCodebook& cb, const std::vector<Descriptor>& descriptors) {
  if (descriptors.empty()) return {};
  return assign(cb.centres, project(cb.pca, standardise(cb.standardiser, descriptor_rows(descriptors))), 1);
}

// ---- Bag of Keypoints -----------------------------------------------------------------------------

Eigen::VectorXd bag_of_keypoints(const std::vector<int>& words, int clusters, bool normalise) {
  Eigen::VectorXd h = Eigen::VectorXd::Zero(clusters);
  for (int w : words)
    if (w >= 0 && w < clusters) h[w] += 1;
  if (normalise && !words.empty()) h /= static_cast<double>(words.size());
  return h;
}

Eigen::VectorXd soft_bag_of_keypoints(const KeypointCodebook& cb, const std::vector<Descriptor>& descriptors, int spread,
                                      bool normalise) {
  const Eigen::Index k = cb.centres.rows();
  Eigen::VectorXd h = Eigen::VectorXd::Zero(k);
  if (descriptors.empty() || k == 0) return h;
  const Eigen::MatrixXd z = project(cb.pca, standardise(cb.standardiser, descriptor_rows(descriptors)));
  const size_t m = static_cast<size_t>(std::clamp<Eigen::Index>(spread, 1, k));
  std::vector<std::pair<double, Eigen::Index>> d(static_cast<size_t>(k));
  for (Eigen::Index i = 0; i < z.rows(); ++i) {
    for (Eigen::Index c = 0; c < k; ++c) d[static_cast<size_t>(c)] = {(cb.centres.row(c) - z.row(i)).norm(), c};
    std::partial_sort(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(m), d.end());
    if (d[0].first <= 1e-12) {  // on a centre: all of it there
      h[d[0].second] += 1;
      continue;
    }
    double total = 0;
    for (size_t j = 0; j < m; ++j) total += 1 / d[j].first;
    for (size_t j = 0; j < m; ++j) h[d[j].second] += (1 / d[j].first) / total;
  }
  if (normalise) h /= static_cast<double>(z.rows());
  return h;
}

// ---- Bag of Graphs --------------------------------------------------------------------------------

double tetrahedron_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Eigen::Vector3d u = (b - a).cast<double>(), v = (c - a).cast<double>(), w = (d - a).cast<double>();
  return std::abs(u.dot(v.cross(w))) / 6.0;
}

std::vector<LocalGraph> local_graphs(const std::vector<Vec3>& positions, const std::vector<int>& words) {
  std::vector<LocalGraph> graphs;
  const size_t n = positions.size();
  if (n < 4 || words.size() != n) return graphs;
  graphs.reserve(n);
  std::vector<std::pair<float, uint32_t>> by_distance(n);
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) by_distance[j] = {(positions[j] - positions[i]).squaredNorm(), static_cast<uint32_t>(j)};
    // The centre itself is at distance 0 and index order breaks ties: skip it explicitly.
    std::partial_sort(by_distance.begin(), by_distance.begin() + 4, by_distance.end());
    std::array<uint32_t, 3> nn{};
    int found = 0;
    for (size_t k = 0; k < 4 && found < 3; ++k)
      if (by_distance[k].second != i) nn[found++] = by_distance[k].second;
    LocalGraph g;
    g.centre = words[i];
    for (int k = 0; k < 3; ++k) g.neighbours[k] = words[nn[k]];
    std::sort(g.neighbours.begin(), g.neighbours.end());  // ordered by cluster number (sec. 3.2.6)
    g.volume = tetrahedron_volume(positions[i], positions[nn[0]], positions[nn[1]], positions[nn[2]]);
    graphs.push_back(g);
  }
  return graphs;
}

namespace {
double log_volume(double v) { return std::log10(std::max(v, 1e-12)); }
}  // namespace

int volume_cluster(const GraphVocabulary& voc, double volume) {
  const double lv = log_volume(volume);
  int best = 0;
  for (int k = 1; k < static_cast<int>(voc.log_volume_centres.size()); ++k)
    if (std::abs(lv - voc.log_volume_centres[k]) < std::abs(lv - voc.log_volume_centres[best])) best = k;
  return best;
}

uint64_t graph_type(const GraphVocabulary& voc, const LocalGraph& g) {
  const uint64_t K = static_cast<uint64_t>(voc.keypoint_clusters);
  uint64_t code = static_cast<uint64_t>(g.centre);
  for (int n : g.neighbours) code = code * K + static_cast<uint64_t>(n);
  return code * std::max<uint64_t>(1, voc.log_volume_centres.size()) + static_cast<uint64_t>(volume_cluster(voc, g.volume));
}

Expected<GraphVocabulary> fit_graph_vocabulary(const std::vector<std::vector<LocalGraph>>& graphs_per_cloud,
                                               int keypoint_clusters, int volume_clusters, uint64_t seed) {
  GraphVocabulary voc;
  voc.keypoint_clusters = keypoint_clusters;
  size_t total = 0;
  for (const auto& g : graphs_per_cloud) total += g.size();
  if (total < static_cast<size_t>(volume_clusters))
    return invalid_argument("Bag of Graphs needs clouds with at least 4 keypoints; training gave " + std::to_string(total) +
                            " graphs for " + std::to_string(volume_clusters) + " volume clusters");
  Eigen::MatrixXd volumes(static_cast<Eigen::Index>(total), 1);
  Eigen::Index row = 0;
  for (const auto& gs : graphs_per_cloud)
    for (const LocalGraph& g : gs) volumes(row++, 0) = log_volume(g.volume);
  KMeansParams km;
  km.k = volume_clusters;
  km.seed = seed;
  km.threads = 1;
  auto clusters = kmeans(volumes, km);
  if (!clusters.ok()) return clusters.error();
  for (Eigen::Index k = 0; k < clusters->centres.rows(); ++k) voc.log_volume_centres.push_back(clusters->centres(k, 0));
  std::sort(voc.log_volume_centres.begin(), voc.log_volume_centres.end());
  for (const auto& gs : graphs_per_cloud)
    for (const LocalGraph& g : gs) voc.types.push_back(graph_type(voc, g));
  std::sort(voc.types.begin(), voc.types.end());
  voc.types.erase(std::unique(voc.types.begin(), voc.types.end()), voc.types.end());
  return voc;
}

Eigen::VectorXd bag_of_graphs(const std::vector<LocalGraph>& graphs, const GraphVocabulary& voc, bool normalise) {
  Eigen::VectorXd h = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(voc.types.size()));
  for (const LocalGraph& g : graphs) {
    const auto it = std::lower_bound(voc.types.begin(), voc.types.end(), graph_type(voc, g));
    if (it != voc.types.end() && *it == graph_type(voc, g)) h[it - voc.types.begin()] += 1;
  }
  if (normalise && !graphs.empty()) h /= static_cast<double>(graphs.size());
  return h;
}

// ---- KGH ------------------------------------------------------------------------------------------

Eigen::VectorXd keypoint_global_histogram(const std::vector<Vec3>& positions, const std::vector<int>& words,
                                          int clusters, int bins, float max_distance_m, bool normalise) {
  Eigen::VectorXd h = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(clusters) * clusters * bins);
  const size_t n = std::min(positions.size(), words.size());
  double pairs = 0;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const float d = (positions[i] - positions[j]).norm();
      const int b = std::min(bins - 1, static_cast<int>(d / max_distance_m * static_cast<float>(bins)));
      // Both orders, so the (word, word) matrix is symmetric as in the paper's 64 x 15 layout.
      h[(static_cast<Eigen::Index>(words[i]) * clusters + words[j]) * bins + b] += 1;
      h[(static_cast<Eigen::Index>(words[j]) * clusters + words[i]) * bins + b] += 1;
      pairs += 2;
    }
  if (normalise && pairs > 0) h /= pairs;
  return h;
}

}  // namespace glimpse
