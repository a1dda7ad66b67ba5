// The decision stage's training cost: fit_decision with every training vector a reference computes
// each vector's distance to the nearest one of another object (its temperature), quadratic in the
// training vectors. With training views from three elevations and their prefixes a SHREC fold holds
// ~20k vectors, and the model's calibration fits four more stages. BM_NearestOtherObjectRowwise is a
// row-at-a-time loop and BM_NearestOtherObjectColumnPass a one-query column-wise pass, the baselines of
// the tiled passes fit_decision makes, run in the same process. BM_DecideRows: calibration's held-out
// decisions, 32 queries a tiled pass, against BM_DecideOneByOne, decide_with_distances per query.
// BM_FitPcaAndProject: the stage's PCA on 1 and 2 threads.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "glimpse/learning/codebook.h"
#include "glimpse/learning/decision.h"

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

// The training vectors projected by the PCA fit_decision fits (0.98 of the variance, at most 65 dims);
// no rows when the PCA fails.
Eigen::MatrixXd projected(const Training& t) {
  auto pca = fit_pca(t.histograms, 0.98, 65);
  return pca.ok() ? project(*pca, t.histograms) : Eigen::MatrixXd();
}

// The baseline: the former nearest-other-object loop (a row of a column-major matrix at a time), on
// vectors projected by the same PCA, so only the loop differs.
// The stage's PCA alone on a model's worth of vectors (21440, as SHREC -> PSB trains): the scatter
// matrix's entries and the projection shared among 1 or 2 threads (the same bits; same-run ratio).
void BM_FitPcaAndProject(benchmark::State& state) {
  const Training t = training(21440);
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    auto pca = fit_pca(t.histograms, 0.98, -1, 1, threads);
    if (!pca.ok()) state.SkipWithError("fit_pca failed");
    benchmark::DoNotOptimize(project(*pca, t.histograms, threads));
  }
}
BENCHMARK(BM_FitPcaAndProject)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_NearestOtherObjectRowwise(benchmark::State& state) {
  const Training t = training(static_cast<int>(state.range(0)));
  const Eigen::MatrixXd y = projected(t);
  if (y.rows() == 0) return state.SkipWithError("fit_pca failed");
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

// The baseline of the tiled passes: each row's distances to every row in one column-wise pass, one row
// at a time, rows shared among threads.
void BM_NearestOtherObjectColumnPass(benchmark::State& state) {
  const Training t = training(static_cast<int>(state.range(0)));
  const Eigen::MatrixXd y = projected(t);
  if (y.rows() == 0) return state.SkipWithError("fit_pca failed");
  const int threads = static_cast<int>(state.range(1));
  for (auto _ : state) {
    std::vector<double> nearest(static_cast<size_t>(y.rows()), INFINITY);
#pragma omp parallel num_threads(threads)
    {
      Eigen::ArrayXd dist;
#pragma omp for schedule(dynamic, 16)
      for (Eigen::Index i = 0; i < y.rows(); ++i) {
        dist.setZero(y.rows());
        for (Eigen::Index c = 0; c < y.cols(); ++c) dist += (y.col(c).array() - y(i, c)).abs();
        double best = INFINITY;
        for (Eigen::Index j = 0; j < y.rows(); ++j)
          if (j != i && t.groups[static_cast<size_t>(i)] != t.groups[static_cast<size_t>(j)]) best = std::min(best, dist[j]);
        nearest[static_cast<size_t>(i)] = best;
      }
    }
    benchmark::DoNotOptimize(nearest);
  }
}
BENCHMARK(BM_NearestOtherObjectColumnPass)->Args({8000, 1})->Args({8000, 2})->Unit(benchmark::kMillisecond);

// 2000 held-out queries against a stage of 8000 references.
struct Decisions {
  DecisionStage stage;
  Eigen::MatrixXd queries;
  std::vector<Eigen::Index> rows;
};
Decisions decisions() {
  const Training t = training(10000);
  DecisionParams p;
  p.pca_explained_variance = 0.98;
  Decisions d;
  d.stage = *fit_decision(t.histograms.topRows(8000), std::vector<int>(t.labels.begin(), t.labels.begin() + 8000), 5, p,
                          42, 0, std::vector<int>(t.groups.begin(), t.groups.begin() + 8000));
  d.queries = t.histograms.bottomRows(2000);
  for (Eigen::Index r = 0; r < d.queries.rows(); ++r) d.rows.push_back(r);
  return d;
}

void BM_DecideOneByOne(benchmark::State& state) {
  const Decisions d = decisions();
  for (auto _ : state) {
    double sum = 0;
    for (Eigen::Index r : d.rows) sum += decide_with_distances(d.stage, d.queries.row(r).transpose()).nearest_distance[0];
    benchmark::DoNotOptimize(sum);
  }
}
BENCHMARK(BM_DecideOneByOne)->Unit(benchmark::kMillisecond);

void BM_DecideRows(benchmark::State& state) {
  const Decisions d = decisions();
  for (auto _ : state) {
    std::vector<double> first(d.rows.size());
    decide_rows_with_distances(d.stage, d.queries, d.rows, static_cast<int>(state.range(0)),
                               [&](size_t k, StageScores&& s) { first[k] = s.nearest_distance[0]; });
    benchmark::DoNotOptimize(first);
  }
}
BENCHMARK(BM_DecideRows)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
