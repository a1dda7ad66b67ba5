// Statistics for keypoint codebooks and Bag of Features: standardisation, PCA to an orthogonal space
// of chosen dimension, k-means clustering and the distances of the decision stage.
// Sec. 3.2.5 (keypoint descriptors -> PCA -> k-means), sec. 3.3.2/3.3.3 (pattern-count histograms ->
// PCA -> k-means), sec. 4 (decision by L1 distance).
//
// Matrices hold one sample per row. Every function is deterministic: k-means takes an explicit seed,
// and results are bit-identical for any thread count (parallel loops write to preallocated slots;
// every sum runs in a fixed order; no Eigen matrix-matrix products, whose blocking depends on the
// number of OpenMP threads).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "glimpse/expected.h"

namespace glimpse {

// ---- Standardisation: zero mean, unit (population) standard deviation per column.

struct Standardiser {
  Eigen::VectorXd mean;   // per column
  Eigen::VectorXd scale;  // per-column standard deviation; 1 for (near-)constant columns
};

// Zero rows give mean 0 and scale 1 for every column (the identity transform).
Standardiser fit_standardiser(const Eigen::MatrixXd& rows);
// (rows - mean) / scale, row by row. rows.cols() must equal s.mean.size() (asserted).
Eigen::MatrixXd standardise(const Standardiser& s, const Eigen::MatrixXd& rows);
Eigen::VectorXd standardise_row(const Standardiser& s, const Eigen::VectorXd& row);

// ---- PCA (sec. 3.2.5, 3.3.2)

struct Pca {
  Eigen::VectorXd mean;       // d, subtracted before projecting
  Eigen::MatrixXd basis;      // d x k, orthonormal columns in decreasing order of variance
  Eigen::VectorXd explained;  // k, fraction of the total variance each kept component explains
};

// Keeps the fewest leading components whose cumulative explained-variance fraction reaches
// `explained_variance` (in (0, 1]; 1 keeps every component of non-zero variance), then clamps the
// count to [min_components, max_components] (max_components < 0: no upper limit). The count never
// exceeds the rank of the centred data: directions of zero variance are undefined.
// Sign convention: the largest-magnitude entry of each basis column is positive (first one on ties).
// With fewer rows than dimensions (e.g. 100 sparse 1000-bin histograms) it diagonalises the n x n
// Gram matrix instead of the d x d covariance.
// Errors (kInvalidArgument): fewer than 2 rows, non-finite entries, zero total variance (all rows
// identical), explained_variance outside (0, 1], min_components < 1, max_components == 0 or
// max_components < min_components. `threads` (<= 0: all) share the scatter matrix's entries, each
// summed alone: the same bits whatever the count.
Expected<Pca> fit_pca(const Eigen::MatrixXd& rows, double explained_variance, int max_components = -1,
                      int min_components = 1, int threads = 1);
// (rows - mean) * basis: n x k. rows.cols() must equal pca.mean.size() (asserted). Rows shared among
// `threads` (<= 0: all).
Eigen::MatrixXd project(const Pca& pca, const Eigen::MatrixXd& rows, int threads = 1);
Eigen::VectorXd project_row(const Pca& pca, const Eigen::VectorXd& row);

// ---- k-means (sec. 3.2.5, 3.3.3)

struct KMeansParams {
  int k = 0;                 // number of clusters (required); at most the number of distinct rows
  int restarts = 4;          // independent k-means++ seedings; the lowest inertia wins
  int max_iterations = 100;  // Lloyd iterations per restart
  double tolerance = 1e-6;   // stop when the summed squared centre shift < tolerance x mean column variance
  uint64_t seed = 1;
  int threads = 0;           // OpenMP threads for the assignment step; 0 = all; results do not depend on it
};

struct KMeansResult {
  Eigen::MatrixXd centres;  // k x d
  std::vector<int> labels;  // per row, index of its nearest centre (L2)
  double inertia = 0;       // sum of squared L2 distances of rows to their centres
  int iterations = 0;       // Lloyd iterations of the winning restart
};

// k-means++ seeding, Lloyd iterations, `restarts` restarts keeping the lowest inertia (the first on
// ties). A cluster that empties is re-seeded with the row farthest from its centre.
// Errors (kInvalidArgument): no rows, non-finite entries, k < 1, restarts < 1, max_iterations < 1,
// tolerance < 0, or k greater than the number of distinct rows (no silent cap: centres.rows() == k).
Expected<KMeansResult> kmeans(const Eigen::MatrixXd& rows, const KMeansParams& params);

// Index of the nearest centre (rows of `centres`), the lowest index on ties; -1 if there are none.
int nearest_centre(const Eigen::MatrixXd& centres, const Eigen::VectorXd& x);  // L2
// nearest_centre for every row of `rows`; threads as in KMeansParams.
std::vector<int> assign(const Eigen::MatrixXd& centres, const Eigen::MatrixXd& rows, int threads = 0);

// ---- Distances of the decision stage. Sizes must match (asserted; +infinity in release builds).

double l1(const Eigen::VectorXd& a, const Eigen::VectorXd& b);  // sec. 4: robust to occlusion
// Float overload for descriptors such as vfh() / esf() (accumulated in double).
double l1(const Eigen::VectorXf& a, const Eigen::VectorXf& b);

}  // namespace glimpse
