#include "glimpse/learning/codebook.h"

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>

#include "glimpse/random.h"

namespace glimpse {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

int resolve_threads(int threads) { return threads > 0 ? threads : std::max(1, omp_get_max_threads()); }

bool all_finite(const MatrixXd& m) { return m.allFinite(); }

// Plain loops in a fixed order: bit-identical whatever Eigen's vectorisation or thread settings.
double dot(const double* a, const double* b, Index d) {
  double s = 0;
  for (Index j = 0; j < d; ++j) s += a[j] * b[j];
  return s;
}

double squared_l2(const double* a, const double* b, Index d) {
  double s = 0;
  for (Index j = 0; j < d; ++j) {
    const double t = a[j] - b[j];
    s += t * t;
  }
  return s;
}

double sum_abs_diff(const double* a, const double* b, Index d) {
  double s = 0;
  for (Index j = 0; j < d; ++j) s += std::abs(a[j] - b[j]);
  return s;
}

Index uniform_index(std::mt19937_64& rng, Index n) {
  return static_cast<Index>((static_cast<unsigned __int128>(rng()) * static_cast<uint64_t>(n)) >> 64);
}

Index count_distinct_columns(const MatrixXd& x) {  // x is d x n, one sample per column
  std::vector<Index> order(static_cast<size_t>(x.cols()));
  std::iota(order.begin(), order.end(), Index{0});
  const Index d = x.rows();
  auto less = [&](Index a, Index b) {
    return std::lexicographical_compare(x.col(a).data(), x.col(a).data() + d, x.col(b).data(),
                                        x.col(b).data() + d);
  };
  std::sort(order.begin(), order.end(), less);
  Index distinct = order.empty() ? 0 : 1;
  for (size_t i = 1; i < order.size(); ++i) distinct += less(order[i - 1], order[i]) ? 1 : 0;
  return distinct;
}

// Nearest centre (columns of c) of every sample (columns of x); writes preallocated slots.
void assign_columns(const MatrixXd& c, const MatrixXd& x, int threads, std::vector<int>& labels,
                    std::vector<double>& dist) {
  const Index d = x.rows(), n = x.cols(), k = c.cols();
#pragma omp parallel for num_threads(threads) schedule(static)
  for (Index i = 0; i < n; ++i) {
    int best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (Index j = 0; j < k; ++j) {
      const double dj = squared_l2(x.col(i).data(), c.col(j).data(), d);
      if (dj < best_d) {
        best_d = dj;
        best = static_cast<int>(j);
      }
    }
    labels[static_cast<size_t>(i)] = best;
    dist[static_cast<size_t>(i)] = best_d;
  }
}

// k-means++ seeding (Arthur & Vassilvitskii 2007): each new centre drawn with probability ~ D^2.
MatrixXd seed_plus_plus(const MatrixXd& x, int k, std::mt19937_64& rng) {
  const Index d = x.rows(), n = x.cols();
  MatrixXd c(d, k);
  c.col(0) = x.col(uniform_index(rng, n));
  std::vector<double> d2(static_cast<size_t>(n));
  for (Index i = 0; i < n; ++i) d2[i] = squared_l2(x.col(i).data(), c.col(0).data(), d);
  for (int j = 1; j < k; ++j) {
    const double total = std::accumulate(d2.begin(), d2.end(), 0.0);
    const double target = uniform01(rng) * total;
    Index pick = -1;
    double cumulative = 0;
    for (Index i = 0; i < n; ++i) {
      cumulative += d2[i];
      if (d2[i] > 0 && cumulative > target) {
        pick = i;
        break;
      }
    }
    if (pick < 0) {  // rounding left target beyond the sum: take the last row not yet a centre
      for (Index i = n - 1; i >= 0 && pick < 0; --i)
        if (d2[i] > 0) pick = i;
    }
    c.col(j) = x.col(pick);  // k <= distinct rows guarantees some d2 > 0
    for (Index i = 0; i < n; ++i)
      d2[i] = std::min(d2[i], squared_l2(x.col(i).data(), c.col(j).data(), d));
  }
  return c;
}

struct Run {
  MatrixXd centres;  // d x k
  std::vector<int> labels;
  double inertia = 0;
  int iterations = 0;
};

Run lloyd(const MatrixXd& x, MatrixXd c, const KMeansParams& p, double shift_tolerance, int threads) {
  const Index d = x.rows(), n = x.cols(), k = c.cols();
  std::vector<int> labels(static_cast<size_t>(n));
  std::vector<double> dist(static_cast<size_t>(n));
  std::vector<Index> counts(static_cast<size_t>(k));
  int it = 0;
  while (it < p.max_iterations) {
    ++it;
    assign_columns(c, x, threads, labels, dist);
    std::fill(counts.begin(), counts.end(), 0);
    for (int l : labels) ++counts[l];
    // An empty cluster takes the row farthest from its centre (first on ties) from a cluster of >= 2.
    for (Index j = 0; j < k; ++j) {
      if (counts[j] > 0) continue;
      Index far = -1;
      for (Index i = 0; i < n; ++i)
        if (counts[labels[i]] > 1 && (far < 0 || dist[i] > dist[far])) far = i;
      if (far < 0) break;  // unreachable while k <= n
      --counts[labels[far]];
      labels[far] = static_cast<int>(j);
      dist[far] = 0;
      counts[j] = 1;
    }
    MatrixXd sums = MatrixXd::Zero(d, k);
    for (Index i = 0; i < n; ++i) sums.col(labels[i]) += x.col(i);
    double shift = 0;
    for (Index j = 0; j < k; ++j) {
      if (counts[j] == 0) continue;  // keeps its centre
      const VectorXd updated = sums.col(j) / static_cast<double>(counts[j]);
      shift += squared_l2(updated.data(), c.col(j).data(), d);
      c.col(j) = updated;
    }
    if (shift <= shift_tolerance) break;
  }
  assign_columns(c, x, threads, labels, dist);
  Run run;
  run.inertia = std::accumulate(dist.begin(), dist.end(), 0.0);
  run.centres = std::move(c);
  run.labels = std::move(labels);
  run.iterations = it;
  return run;
}

template <class Vec>
double checked_size(const Vec& a, const Vec& b) {
  assert(a.size() == b.size());
  return a.size() == b.size() ? 0.0 : std::numeric_limits<double>::infinity();
}

}  // namespace

// ---- Standardisation

Standardiser fit_standardiser(const MatrixXd& rows) {
  const Index n = rows.rows(), d = rows.cols();
  Standardiser s{VectorXd::Zero(d), VectorXd::Ones(d)};
  if (n == 0) return s;
  for (Index j = 0; j < d; ++j) {
    double sum = 0;
    for (Index i = 0; i < n; ++i) sum += rows(i, j);
    const double mean = sum / static_cast<double>(n);
    double ss = 0;
    for (Index i = 0; i < n; ++i) ss += (rows(i, j) - mean) * (rows(i, j) - mean);
    const double sd = std::sqrt(ss / static_cast<double>(n));
    s.mean[j] = mean;
    // A constant column leaves only rounding noise: scale 1 keeps it at ~0 instead of amplifying it.
    s.scale[j] = (sd > 1e-12 * std::max(1.0, std::abs(mean))) ? sd : 1.0;
  }
  return s;
}

MatrixXd standardise(const Standardiser& s, const MatrixXd& rows) {
  assert(rows.cols() == s.mean.size());
  MatrixXd out(rows.rows(), rows.cols());
  for (Index j = 0; j < rows.cols(); ++j)
    for (Index i = 0; i < rows.rows(); ++i) out(i, j) = (rows(i, j) - s.mean[j]) / s.scale[j];
  return out;
}

VectorXd standardise_row(const Standardiser& s, const VectorXd& row) {
  assert(row.size() == s.mean.size());
  return ((row - s.mean).array() / s.scale.array()).matrix();
}

// ---- PCA

Expected<Pca> fit_pca(const MatrixXd& rows, double explained_variance, int max_components,
                      int min_components, int threads) {
  const Index n = rows.rows(), d = rows.cols();
  if (n < 2 || d < 1)
    return invalid_argument("fit_pca: needs at least 2 rows of at least 1 column, got " +
                            std::to_string(n) + "x" + std::to_string(d));
  if (!all_finite(rows)) return invalid_argument("fit_pca: input has NaN or Inf entries");
  if (!(explained_variance > 0 && explained_variance <= 1))
    return invalid_argument("fit_pca: explained_variance must be in (0, 1]");
  if (min_components < 1) return invalid_argument("fit_pca: min_components must be >= 1");
  if (max_components == 0 || (max_components > 0 && max_components < min_components))
    return invalid_argument("fit_pca: max_components must be < 0 (no limit) or >= min_components");

  Pca pca;
  pca.mean = VectorXd::Zero(d);
  for (Index i = 0; i < n; ++i)
    for (Index j = 0; j < d; ++j) pca.mean[j] += rows(i, j);
  pca.mean /= static_cast<double>(n);
  MatrixXd xt(d, n);  // centred samples as contiguous columns
  for (Index i = 0; i < n; ++i) xt.col(i) = rows.row(i).transpose() - pca.mean;
  double total = 0;  // trace of the scatter matrix
  for (Index i = 0; i < n; ++i) total += dot(xt.col(i).data(), xt.col(i).data(), d);
  if (!(total > 0)) return invalid_argument("fit_pca: zero total variance (all rows identical)");

  // Eigenvalues of the scatter matrix, largest first, with unit eigenvectors in `vectors` (d x m).
  VectorXd values;
  MatrixXd vectors;
  if (n < d) {
    // Fewer samples than dimensions: diagonalise the n x n Gram matrix, v = X^T u / sqrt(lambda).
    MatrixXd gram(n, n);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(dynamic, 8)
    for (Index a = 0; a < n; ++a)
      for (Index b = 0; b <= a; ++b) gram(a, b) = gram(b, a) = dot(xt.col(a).data(), xt.col(b).data(), d);
    Eigen::SelfAdjointEigenSolver<MatrixXd> eig(gram);
    if (eig.info() != Eigen::Success) return internal_error("fit_pca: eigensolver did not converge");
    values = eig.eigenvalues().reverse();
    const MatrixXd u = eig.eigenvectors().rowwise().reverse();
    vectors = MatrixXd::Zero(d, n);
    for (Index c = 0; c < n; ++c) {
      if (!(values[c] > 0)) continue;
      for (Index i = 0; i < n; ++i) vectors.col(c) += u(i, c) * xt.col(i);
      const double norm = std::sqrt(dot(vectors.col(c).data(), vectors.col(c).data(), d));
      if (norm > 0) vectors.col(c) /= norm;
    }
  } else {
    MatrixXd scatter(d, d);
    MatrixXd x = xt.transpose();  // n x d: each column contiguous
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(dynamic, 1)
    for (Index a = 0; a < d; ++a)
      for (Index b = 0; b <= a; ++b) scatter(a, b) = scatter(b, a) = dot(x.col(a).data(), x.col(b).data(), n);
    Eigen::SelfAdjointEigenSolver<MatrixXd> eig(scatter);
    if (eig.info() != Eigen::Success) return internal_error("fit_pca: eigensolver did not converge");
    values = eig.eigenvalues().reverse();
    vectors = eig.eigenvectors().rowwise().reverse();
  }

  // Rank: components whose variance is above rounding noise of the largest one.
  const double noise = values[0] * 1e-12 * static_cast<double>(std::max(n, d));
  Index rank = 0;
  while (rank < values.size() && values[rank] > noise) ++rank;
  Index k = 0;
  double cumulative = 0;
  while (k < rank && cumulative < explained_variance * total * (1 - 1e-12)) cumulative += values[k++];
  k = std::max<Index>(k, min_components);
  if (max_components > 0) k = std::min<Index>(k, max_components);
  k = std::max<Index>(1, std::min(k, rank));

  pca.basis = vectors.leftCols(k);
  pca.explained = values.head(k) / total;
  for (Index c = 0; c < k; ++c) {  // sign convention: the largest-magnitude entry is positive
    Index arg = 0;
    for (Index j = 1; j < d; ++j)
      if (std::abs(pca.basis(j, c)) > std::abs(pca.basis(arg, c))) arg = j;
    if (pca.basis(arg, c) < 0) pca.basis.col(c) = -pca.basis.col(c);
  }
  return pca;
}

MatrixXd project(const Pca& pca, const MatrixXd& rows, int threads) {
  assert(rows.cols() == pca.mean.size());
  const Index n = rows.rows(), d = rows.cols(), k = pca.basis.cols();
  MatrixXd out(n, k);
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static, 256)
  for (Index i = 0; i < n; ++i) {
    thread_local VectorXd centred;
    centred.resize(d);
    for (Index j = 0; j < d; ++j) centred[j] = rows(i, j) - pca.mean[j];
    for (Index c = 0; c < k; ++c) out(i, c) = dot(centred.data(), pca.basis.col(c).data(), d);
  }
  return out;
}

VectorXd project_row(const Pca& pca, const VectorXd& row) {
  assert(row.size() == pca.mean.size());
  const VectorXd centred = row - pca.mean;
  VectorXd out(pca.basis.cols());
  for (Index c = 0; c < out.size(); ++c) out[c] = dot(centred.data(), pca.basis.col(c).data(), centred.size());
  return out;
}

// ---- k-means

Expected<KMeansResult> kmeans(const MatrixXd& rows, const KMeansParams& p) {
  const Index n = rows.rows(), d = rows.cols();
  if (n == 0 || d == 0) return invalid_argument("kmeans: no rows");
  if (p.k < 1) return invalid_argument("kmeans: k must be >= 1");
  if (p.restarts < 1) return invalid_argument("kmeans: restarts must be >= 1");
  if (p.max_iterations < 1) return invalid_argument("kmeans: max_iterations must be >= 1");
  if (!(p.tolerance >= 0)) return invalid_argument("kmeans: tolerance must be >= 0");
  if (!all_finite(rows)) return invalid_argument("kmeans: input has NaN or Inf entries");
  const MatrixXd x = rows.transpose();  // d x n: samples as contiguous columns
  if (p.k > n || count_distinct_columns(x) < p.k)
    return invalid_argument("kmeans: k = " + std::to_string(p.k) + " exceeds the number of distinct rows");

  // Tolerance relative to the data's scale, as scikit-learn: tolerance x mean column variance.
  double mean_variance = 0;
  const Standardiser s = fit_standardiser(rows);
  for (Index j = 0; j < d; ++j) {
    double ss = 0;
    for (Index i = 0; i < n; ++i) ss += (x(j, i) - s.mean[j]) * (x(j, i) - s.mean[j]);
    mean_variance += ss / static_cast<double>(n);
  }
  mean_variance /= static_cast<double>(d);
  const double shift_tolerance = p.tolerance * mean_variance;
  const int threads = resolve_threads(p.threads);

  Run best;
  for (int r = 0; r < p.restarts; ++r) {
    std::mt19937_64 rng(splitmix64(p.seed + 0x632be59bd9b4e019ULL * static_cast<uint64_t>(r)));
    Run run = lloyd(x, seed_plus_plus(x, p.k, rng), p, shift_tolerance, threads);
    if (r == 0 || run.inertia < best.inertia) best = std::move(run);
  }
  return KMeansResult{best.centres.transpose(), std::move(best.labels), best.inertia, best.iterations};
}

int nearest_centre(const MatrixXd& centres, const VectorXd& x) {
  assert(centres.rows() == 0 || centres.cols() == x.size());
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (Index j = 0; j < centres.rows(); ++j) {
    const VectorXd c = centres.row(j).transpose();
    const double dj = squared_l2(c.data(), x.data(), x.size());
    if (best < 0 || dj < best_d) {
      best_d = dj;
      best = static_cast<int>(j);
    }
  }
  return best;
}

std::vector<int> assign(const MatrixXd& centres, const MatrixXd& rows, int threads) {
  std::vector<int> labels(static_cast<size_t>(rows.rows()), -1);
  if (centres.rows() == 0 || rows.rows() == 0) return labels;
  assert(centres.cols() == rows.cols());
  std::vector<double> dist(labels.size());
  assign_columns(centres.transpose(), rows.transpose(), resolve_threads(threads), labels, dist);
  return labels;
}

// ---- Distances

double l1(const VectorXd& a, const VectorXd& b) {
  if (double bad = checked_size(a, b); bad != 0) return bad;
  return sum_abs_diff(a.data(), b.data(), a.size());
}

double l1(const Eigen::VectorXf& a, const Eigen::VectorXf& b) { return l1(VectorXd(a.cast<double>()), VectorXd(b.cast<double>())); }

}  // namespace glimpse
