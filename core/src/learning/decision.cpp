#include "glimpse/learning/decision.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <string>

namespace glimpse {

int argmax(const Eigen::VectorXd& scores) {
  int best = 0;
  for (int i = 1; i < scores.size(); ++i)
    if (scores[i] > scores[best]) best = i;
  return scores.size() ? best : -1;
}

namespace {

double l1_rows(const Eigen::MatrixXd& m, Eigen::Index i, const Eigen::VectorXd& x) {
  return (m.row(i).transpose() - x).lpNorm<1>();
}

// L1 distances from x to every row of m, accumulated column by column: each column is contiguous in
// Eigen's column-major storage, so this runs at memory speed where a row at a time strides across it.
template <typename Vector>
void l1_to_rows(const Eigen::MatrixXd& m, const Vector& x, Eigen::ArrayXd& out) {
  out.setZero(m.rows());
  for (Eigen::Index c = 0; c < m.cols(); ++c) out += (m.col(c).array() - x[c]).abs();
}

// L1 distances from each row of x (a few queries) to every row of m, into the columns of out (m's rows
// x queries): blocks of kRows references against kQueries queries at a time, the sums held in
// registers, every group of queries taken in turn while the block's columns are in the cache (the
// matrix is read from memory once per call, not once per group; l1_to_rows streams the whole matrix
// and its sums through memory per query). Every distance adds its columns in order from zero, as
// l1_to_rows, so the two give the same bits. Plain loops the compiler vectorises, built twice: AVX2
// where the processor has it, SSE2 otherwise (the same operations element by element either way).
__attribute__((target_clones("avx2", "default")))
void l1_to_rows_many(const Eigen::MatrixXd& m, const Eigen::MatrixXd& x, Eigen::ArrayXXd& out) {
  constexpr int kRows = 8, kQueries = 4;
  const Eigen::Index n = m.rows(), d = m.cols(), queries = x.rows();
  out.resize(n, queries);
  if (queries == 0) return;
  const Eigen::Index groups = (queries + kQueries - 1) / kQueries;
  // xq[(g * d + c) * kQueries + q]: group g's queries column by column, the last group padded with
  // copies of its last query (computed and dropped).
  std::vector<double> xq(static_cast<size_t>(groups * d * kQueries));
  for (Eigen::Index g = 0; g < groups; ++g)
    for (int q = 0; q < kQueries; ++q)
      for (Eigen::Index c = 0; c < d; ++c)
        xq[static_cast<size_t>((g * d + c) * kQueries + q)] = x(std::min<Eigen::Index>(g * kQueries + q, queries - 1), c);
  Eigen::Index j0 = 0;
  for (; j0 + kRows <= n; j0 += kRows)
    for (Eigen::Index g = 0; g < groups; ++g) {
      double acc[kQueries][kRows] = {};
      const double* xg = xq.data() + g * d * kQueries;
      for (Eigen::Index c = 0; c < d; ++c) {
        const double* column = m.data() + c * n + j0;
        const double* xc = xg + c * kQueries;
        for (int q = 0; q < kQueries; ++q)
          for (int j = 0; j < kRows; ++j) acc[q][j] += std::abs(column[j] - xc[q]);
      }
      const int count = static_cast<int>(std::min<Eigen::Index>(kQueries, queries - g * kQueries));
      for (int q = 0; q < count; ++q)
        for (int j = 0; j < kRows; ++j) out(j0 + j, g * kQueries + q) = acc[q][j];
    }
  for (; j0 < n; ++j0)
    for (Eigen::Index k = 0; k < queries; ++k) {
      double sum = 0;
      for (Eigen::Index c = 0; c < d; ++c) sum += std::abs(m(j0, c) - x(k, c));
      out(j0, k) = sum;
    }
}
// Queries per pass over the references, each block of references read from memory once for all of
// them (32 with the groups inside the blocks against 8 per pass: bench_decision BM_DecideRows/2 0.61x).
constexpr Eigen::Index kQueriesPerPass = 32;

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

namespace {

// The stage's projection: PCA of the training histograms, or none (L1 on the histograms themselves: the
// identity projection).
Status fit_projection(DecisionStage& st, const Eigen::MatrixXd& histograms, const DecisionParams& params, int threads) {
  if (params.pca_explained_variance > 0) {
    auto pca = fit_pca(histograms, params.pca_explained_variance, params.max_pca_dims, 1, threads);
    if (!pca.ok()) return pca.error();
    st.pca = std::move(*pca);
    return {};
  }
  st.projected = false;
  const Eigen::Index d = histograms.cols();
  st.pca.mean = Eigen::VectorXd::Zero(d);
  st.pca.basis = Eigen::MatrixXd::Identity(d, d);
  st.pca.explained = Eigen::VectorXd::Constant(d, 1.0 / static_cast<double>(std::max<Eigen::Index>(d, 1)));
  return {};
}

// Every training vector a reference. The scale: per query, the distance from a training vector to its
// nearest one of another object (the distance a new object is from the training set; another view of
// the same object is closer). Quadratic in the training vectors (tens of thousands with several
// elevations and prefixes), so the queries are params.temperature_queries of them, evenly spaced in
// training order (each against every vector): a few rows' distances per pass over the rows
// (l1_to_rows_many), passes shared among threads (each writes its own slots: the result does not depend
// on the thread count).
std::vector<double> nearest_other_object(const Eigen::MatrixXd& y, const DecisionParams& params, int threads,
                                         const std::vector<int>& groups) {
  auto same_object = [&](Eigen::Index i, Eigen::Index j) {
    return !groups.empty() && groups[static_cast<size_t>(i)] == groups[static_cast<size_t>(j)];
  };
  const Eigen::Index n = y.rows();
  const Eigen::Index m = params.temperature_queries > 0 ? std::min<Eigen::Index>(n, params.temperature_queries) : n;
  auto query = [&](Eigen::Index k) { return k * n / m; };  // the k-th of the m, in training order
  std::vector<double> nearest(static_cast<size_t>(m), INFINITY);
  const int workers = threads > 0 ? threads : std::max(1, omp_get_max_threads());
  const Eigen::Index passes = (m + kQueriesPerPass - 1) / kQueriesPerPass;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 2)
  for (Eigen::Index pass = 0; pass < passes; ++pass) {
    const Eigen::Index first = pass * kQueriesPerPass, count = std::min(kQueriesPerPass, m - first);
    Eigen::MatrixXd rows(count, y.cols());
    for (Eigen::Index q = 0; q < count; ++q) rows.row(q) = y.row(query(first + q));
    Eigen::ArrayXXd dist;
    l1_to_rows_many(y, rows, dist);
    for (Eigen::Index q = 0; q < count; ++q) {
      const Eigen::Index i = query(first + q);
      double best = INFINITY;
      for (Eigen::Index j = 0; j < n; ++j)
        if (j != i && !same_object(i, j)) best = std::min(best, dist(j, q));
      nearest[static_cast<size_t>(first + q)] = best;
    }
  }
  std::vector<double> scale;
  for (double best : nearest)
    if (std::isfinite(best)) scale.push_back(best);
  return scale;
}

// K-means centres of each category's training vectors (sec. 3.3.3); one per category = the paper. The
// scale: per training vector, the distance to its category's nearest centre.
std::vector<double> category_centres(DecisionStage& st, const Eigen::MatrixXd& y, const std::vector<int>& labels,
                                     const std::vector<int>& per_category, const DecisionParams& params,
                                     uint64_t seed, int threads) {
  const int per = params.kind == DecisionRule::kNearestCentre ? 1 : std::max(1, params.centres_per_category);
  std::vector<Eigen::VectorXd> centres;
  for (int c = 0; c < st.categories; ++c) {
    Eigen::MatrixXd rows(per_category[c], y.cols());
    Eigen::Index r = 0;
    for (size_t i = 0; i < labels.size(); ++i)
      if (labels[i] == c) rows.row(r++) = y.row(static_cast<Eigen::Index>(i));
    KMeansParams km;
    km.k = std::min<int>(per, static_cast<int>(rows.rows()));
    km.seed = seed + static_cast<uint64_t>(c);
    km.threads = threads;
    Eigen::MatrixXd found;
    if (km.k == 1) {
      found = rows.colwise().mean();
    } else {
      auto result = kmeans(rows, km);
      found = result.ok() ? result->centres : Eigen::MatrixXd(rows.colwise().mean());
    }
    for (Eigen::Index k = 0; k < found.rows(); ++k) {
      centres.push_back(found.row(k).transpose());
      st.labels.push_back(c);
    }
  }
  st.references.resize(static_cast<Eigen::Index>(centres.size()), y.cols());
  for (size_t i = 0; i < centres.size(); ++i) st.references.row(static_cast<Eigen::Index>(i)) = centres[i].transpose();
  std::vector<double> scale;
  for (Eigen::Index i = 0; i < y.rows(); ++i) {
    double best = INFINITY;
    for (Eigen::Index k = 0; k < st.references.rows(); ++k)
      if (st.labels[k] == labels[i]) best = std::min(best, l1_rows(st.references, k, y.row(i).transpose()));
    scale.push_back(best);
  }
  return scale;
}

}  // namespace

Expected<DecisionStage> fit_decision(const Eigen::MatrixXd& histograms, const std::vector<int>& labels, int categories,
                                     const DecisionParams& params, uint64_t seed, int threads,
                                     const std::vector<int>& groups) {
  if (histograms.rows() != static_cast<Eigen::Index>(labels.size()) || histograms.rows() < 2)
    return invalid_argument("the decision stage needs at least 2 labelled training vectors");
  if (!groups.empty() && groups.size() != labels.size())
    return internal_error("one training object per training vector is needed");
  std::vector<int> per_category(categories, 0);
  for (int l : labels) {
    if (l < 0 || l >= categories) return internal_error("a training label is out of range");
    ++per_category[l];
  }
  for (int c = 0; c < categories; ++c)
    if (per_category[c] == 0) return invalid_argument("category " + std::to_string(c) + " has no training vector");

  DecisionStage st;
  st.kind = params.kind;
  st.categories = categories;
  st.neighbours = std::max(1, params.neighbours);
  if (Status s = fit_projection(st, histograms, params, threads); !s.ok()) return s.error();
  // Training vectors at the precision a model stores its references: the model trained and the model
  // read back decide alike, and the temperature is of the references stored.
  const Eigen::MatrixXd y = stored_precision(project(st.pca, histograms, threads));
  std::vector<double> scale;
  if (params.kind == DecisionRule::kNearestNeighbours || params.kind == DecisionRule::kNearestReference) {
    st.references = y;
    st.labels = labels;
    scale = nearest_other_object(y, params, threads, groups);
  } else {
    scale = category_centres(st, y, labels, per_category, params, seed, threads);
  }
  st.temperature = std::max(median(scale), 1e-9);
  st.references = stored_precision(st.references);  // centres too (training vectors already are)
  return st;
}

Eigen::MatrixXd stored_precision(const Eigen::MatrixXd& references) {
  constexpr double kLargestBinary16 = 65504;
  const bool fits = references.allFinite() && (references.size() == 0 || references.cwiseAbs().maxCoeff() <= kLargestBinary16);
  if (!fits) return references.cast<float>().cast<double>();
  return references.cast<float>().cast<Eigen::half>().cast<float>().cast<double>();
}

bool is_binary16(const Eigen::MatrixXd& m) {
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    const float v = static_cast<float>(m.data()[i]);
    if (!std::isfinite(v) || static_cast<float>(static_cast<Eigen::half>(v)) != v) return false;
  }
  return true;
}

bool is_identity_projection(const Pca& pca) {
  return pca.basis.rows() == pca.basis.cols() && pca.mean.size() == pca.basis.rows() && pca.mean.isZero() &&
         pca.basis.isIdentity();
}

namespace {

// A stage's answer (scores, nearest reference per category) from the query's distance to every
// reference and the temperature those distances are in.
void answer_from_distances(const DecisionStage& st, Eigen::ArrayXd&& dist, double temperature, StageScores& out) {
  const Eigen::Index n = st.references.rows();
  std::vector<std::pair<double, Eigen::Index>> d(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) d[static_cast<size_t>(i)] = {dist[i], i};
  out.distance = std::move(dist);
  Eigen::VectorXd& best = out.nearest_distance;
  best = Eigen::VectorXd::Constant(st.categories, INFINITY);
  out.nearest_reference = Eigen::VectorXi::Constant(st.categories, -1);
  for (const auto& [dist, i] : d) {
    const int c = st.labels[static_cast<size_t>(i)];
    if (dist < best[c]) best[c] = dist, out.nearest_reference[c] = static_cast<int>(i);
  }
  Eigen::VectorXd scores = Eigen::VectorXd::Zero(st.categories);
  if (st.kind == DecisionRule::kNearestNeighbours) {
    const size_t k = std::min<size_t>(static_cast<size_t>(st.neighbours), d.size());
    std::partial_sort(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
    // Votes of the k nearest, each weighted by how close it is relative to the nearest.
    for (size_t i = 0; i < k; ++i)
      scores[st.labels[static_cast<size_t>(d[i].second)]] += std::exp(-(d[i].first - d[0].first) / temperature);
  } else {
    // Softmin over each category's nearest centre (or, for kNearestReference, training vector).
    const double lo = best.minCoeff();
    for (int c = 0; c < st.categories; ++c) scores[c] = std::exp(-(best[c] - lo) / temperature);
  }
  // A small floor keeps every category possible (no hard zero), then scores sum to 1.
  scores.array() += 1e-3;
  out.scores = scores / scores.sum();
}

}  // namespace

StageScores decide_with_distances(const DecisionStage& st, const Eigen::VectorXd& histogram, bool by_shape) {
  const Eigen::Index n = st.references.rows();
  StageScores out;
  if (by_shape && !st.projected) {
    auto unit = [](const Eigen::VectorXd& v) {
      const double mass = v.lpNorm<1>();
      return mass > 0 ? Eigen::VectorXd(v / mass) : v;
    };
    const Eigen::VectorXd y = unit(histogram);
    double mass = 0;
    Eigen::ArrayXd dist(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::VectorXd ref = st.references.row(i).transpose();
      mass += ref.lpNorm<1>();
      dist[i] = (unit(ref) - y).lpNorm<1>();
    }
    // Distances between unit-mass histograms: the temperature in the same units.
    const double temperature = mass > 0 ? st.temperature / (mass / static_cast<double>(n)) : st.temperature;
    answer_from_distances(st, std::move(dist), temperature, out);
    return out;
  }
  const Eigen::VectorXd y = project_row(st.pca, histogram);
  Eigen::ArrayXd dist;
  l1_to_rows(st.references, y, dist);
  out.residual = (histogram - st.pca.mean - st.pca.basis * y).lpNorm<1>();
  answer_from_distances(st, std::move(dist), st.temperature, out);
  return out;
}

void decide_rows_with_distances(const DecisionStage& st, const Eigen::MatrixXd& histograms,
                                const std::vector<Eigen::Index>& rows, int threads,
                                const std::function<void(size_t, StageScores&&)>& visit) {
  const Eigen::Index count = static_cast<Eigen::Index>(rows.size());
  const Eigen::Index passes = (count + kQueriesPerPass - 1) / kQueriesPerPass;
  const int workers = threads > 0 ? threads : std::max(1, omp_get_max_threads());
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
  for (Eigen::Index pass = 0; pass < passes; ++pass) {
    const Eigen::Index first = pass * kQueriesPerPass, k = std::min(kQueriesPerPass, count - first);
    // Each query projected alone, as decide_with_distances does (a product of many rows at once may
    // round otherwise).
    std::vector<StageScores> out(static_cast<size_t>(k));
    Eigen::MatrixXd y;
    for (Eigen::Index q = 0; q < k; ++q) {
      const Eigen::VectorXd h = histograms.row(rows[static_cast<size_t>(first + q)]).transpose();
      const Eigen::VectorXd p = project_row(st.pca, h);
      if (q == 0) y.resize(k, p.size());
      y.row(q) = p.transpose();
      out[static_cast<size_t>(q)].residual = (h - st.pca.mean - st.pca.basis * p).lpNorm<1>();
    }
    Eigen::ArrayXXd dist;
    l1_to_rows_many(st.references, y, dist);
    for (Eigen::Index q = 0; q < k; ++q) {
      answer_from_distances(st, Eigen::ArrayXd(dist.col(q)), st.temperature, out[static_cast<size_t>(q)]);
      visit(static_cast<size_t>(first + q), std::move(out[static_cast<size_t>(q)]));
    }
  }
}

Eigen::VectorXd nearest_objects_distance(const DecisionStage& st, const Eigen::ArrayXd& distance,
                                         const std::vector<uint32_t>& reference_object, const std::vector<int>& objects) {
  const size_t n = static_cast<size_t>(st.references.rows());
  if (distance.size() != st.references.rows() || reference_object.size() != n || st.labels.size() != n ||
      objects.size() != static_cast<size_t>(st.categories))
    return {};
  // Each training object's nearest reference, then per category its `objects` nearest objects.
  const uint32_t count = n ? *std::max_element(reference_object.begin(), reference_object.end()) + 1 : 0;
  std::vector<double> nearest(count, INFINITY);
  std::vector<int> category(count, -1);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t o = reference_object[i];
    nearest[o] = std::min(nearest[o], distance[static_cast<Eigen::Index>(i)]);
    category[o] = st.labels[i];
  }
  std::vector<std::vector<double>> of(static_cast<size_t>(st.categories));
  for (uint32_t o = 0; o < count; ++o)
    if (category[o] >= 0) of[static_cast<size_t>(category[o])].push_back(nearest[o]);
  Eigen::VectorXd out = Eigen::VectorXd::Constant(st.categories, INFINITY);
  for (int c = 0; c < st.categories; ++c) {
    std::vector<double>& v = of[static_cast<size_t>(c)];
    const size_t k = std::min(v.size(), static_cast<size_t>(std::max(1, objects[static_cast<size_t>(c)])));
    if (k == 0) continue;
    std::partial_sort(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    out[c] = std::accumulate(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), 0.0) / double(k);
  }
  return out;
}

Eigen::VectorXd decide(const DecisionStage& st, const Eigen::VectorXd& histogram, bool by_shape) {
  return decide_with_distances(st, histogram, by_shape).scores;
}

}  // namespace glimpse
