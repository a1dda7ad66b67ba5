// The decision stage's training cost: fit_decision with every training vector a reference computes
// each vector's distance to the nearest one of another object (its temperature), quadratic in the
// training vectors. With training views from three elevations and their prefixes a SHREC fold holds
// ~20k vectors, and the model's calibration fits four more stages. BM_NearestOtherObjectRowwise is
// the row-at-a-time loop fit_decision used before, run in the same process as the ratio's baseline.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "glimpse/codebook.h"
#include "glimpse/decision.h"

using namespace glimpse;

namespace {

struct Training {
  Eigen::MatrixXd histograms;  // rows: training vectors
  std::vector<int> labels, groups;
};

// n vectors of 5 categories, 36 per object (6 views x 6 prefixes), 80 dimensions like USH.
Training training(int n) {
  Training t;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0, 1);
  t.histograms.resize(n, 80);
  for (int i = 0; i < n; ++i) {
    t.groups.push_back(i / 36);
    t.labels.push_back((i / 36) % 5);
    for (int c = 0; c < 80; ++c) t.histograms(i, c) = noise(rng) + (c % 5 == t.labels.back() ? 2.0 : 0.0);
  }
  return t;
}

void BM_FitDecisionNearestReference(benchmark::State& state) {
  const Training t = training(static_cast<int>(state.range(0)));
  DecisionParams p;
  p.pca_explained_variance = 0.98;
  for (auto _ : state) {
    auto stage = fit_decision(t.histograms, t.labels, 5, p, 42, static_cast<int>(state.range(1)), t.groups);
    if (!stage.ok()) state.SkipWithError("fit_decision failed");
    benchmark::DoNotOptimize(stage);
  }
}
BENCHMARK(BM_FitDecisionNearestReference)->Args({2000, 1})->Args({8000, 1})->Args({8000, 2})->Unit(benchmark::kMillisecond);

// The baseline: the former nearest-other-object loop (a row of a column-major matrix at a time), on
// vectors projected by the same PCA, so only the loop differs.
void BM_NearestOtherObjectRowwise(benchmark::State& state) {
  const Training t = training(static_cast<int>(state.range(0)));
  auto pca = fit_pca(t.histograms, 0.98, 65);
  if (!pca.ok()) {
    state.SkipWithError("fit_pca failed");
    return;
  }
  const Eigen::MatrixXd y = project(*pca, t.histograms);
  for (auto _ : state) {
    std::vector<double> scale;
    for (Eigen::Index i = 0; i < y.rows(); ++i) {
      double best = INFINITY;
      for (Eigen::Index j = 0; j < y.rows(); ++j)
        if (j != i && t.groups[static_cast<size_t>(i)] != t.groups[static_cast<size_t>(j)]) {
          const Eigen::VectorXd x = y.row(i).transpose();
          best = std::min(best, (y.row(j).transpose() - x).lpNorm<1>());
        }
      scale.push_back(best);
    }
    benchmark::DoNotOptimize(scale);
  }
}
BENCHMARK(BM_NearestOtherObjectRowwise)->Arg(2000)->Arg(8000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
