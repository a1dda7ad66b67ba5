// The global-descriptor baseline (sec. 3.1) other benchmarks compare against: describing a 10k-point
// single view and finding its nearest neighbour (L1, sec. 4) among 100 stored descriptors, with
// (a) PCL's own VFH pipeline as a user writes it (NormalEstimation + VFHEstimation),
// (b) our vfh() and vfh_with_normals() (the local surfaces' normals), (c) our esf() — and PCL's ESFEstimation for reference.
// Run with --benchmark_repetitions=5 --benchmark_report_aggregates_only=true and compare medians.
#include <benchmark/benchmark.h>

#include <random>

#include "scene.h"
#include "glimpse/learning/codebook.h"
#include "glimpse/features/global_descriptors.h"

namespace glimpse {
namespace {

using bench::view10k;

// 100 stored descriptors: random non-negative histograms with the layout's total mass.
std::vector<Eigen::VectorXf> stored(int size, float mass) {
  std::mt19937_64 rng(7);
  std::vector<Eigen::VectorXf> out(100, Eigen::VectorXf(size));
  for (Eigen::VectorXf& h : out) {
    for (int i = 0; i < size; ++i) h[i] = static_cast<float>(rng() >> 40);
    h *= mass / h.sum();
  }
  return out;
}

int nearest(const Eigen::VectorXf& q, const std::vector<Eigen::VectorXf>& db) {
  int best = 0;
  double best_d = l1(q, db[0]);
  for (int i = 1; i < static_cast<int>(db.size()); ++i)
    if (const double d = l1(q, db[i]); d < best_d) best_d = d, best = i;
  return best;
}

void BM_PclVfhPipeline(benchmark::State& state) {
  const Cloud& c = view10k();
  const auto db = stored(kVfhSize, 500);
  for (auto _ : state) {
    auto h = pcl_reference::vfh(c, 0.03f);
    if (!h.ok()) state.SkipWithError(h.error().message.c_str());
    else benchmark::DoNotOptimize(nearest(*h, db));
  }
  state.counters["points"] = static_cast<double>(c.points.size());
}
BENCHMARK(BM_PclVfhPipeline)->Unit(benchmark::kMillisecond);

void BM_GlimpseVfh(benchmark::State& state) {  // arg: threads
  const Cloud& c = view10k();
  const auto db = stored(kVfhSize, 500);
  const GlobalDescriptorParams params{.normal_radius_m = 0.03f, .threads = static_cast<int>(state.range(0))};
  for (auto _ : state) {
    auto h = vfh(c, params);
    if (!h.ok()) state.SkipWithError(h.error().message.c_str());
    else benchmark::DoNotOptimize(nearest(*h, db));
  }
}
BENCHMARK(BM_GlimpseVfh)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_GlimpseVfhAutoRadius(benchmark::State& state) {
  const Cloud& c = view10k();
  const auto db = stored(kVfhSize, 500);
  for (auto _ : state) {
    auto h = vfh(c, {.normal_radius_m = 0, .threads = 1});
    if (!h.ok()) state.SkipWithError(h.error().message.c_str());
    else benchmark::DoNotOptimize(nearest(*h, db));
  }
}
BENCHMARK(BM_GlimpseVfhAutoRadius)->Unit(benchmark::kMillisecond);

// What Classify computes (method_features): VFH over normals the local surfaces already have.
void BM_GlimpseVfhWithNormals(benchmark::State& state) {
  const Cloud& c = view10k();
  const auto db = stored(kVfhSize, 500);
  std::vector<Vec3> normals(c.points.size());
  for (size_t i = 0; i < normals.size(); ++i) normals[i] = (c.points[i] - Vec3(0, 0, 1)).normalized();
  for (auto _ : state) {
    auto h = vfh_with_normals(c, normals, {.threads = 1});
    if (!h.ok()) state.SkipWithError(h.error().message.c_str());
    else benchmark::DoNotOptimize(nearest(*h, db));
  }
}
BENCHMARK(BM_GlimpseVfhWithNormals)->Unit(benchmark::kMillisecond);

void BM_GlimpseEsf(benchmark::State& state) {
  const Cloud& c = view10k();
  const auto db = stored(kEsfSize, 1);
  for (auto _ : state) {
    auto h = esf(c, 1);
    if (!h.ok()) state.SkipWithError(h.error().message.c_str());
    else benchmark::DoNotOptimize(nearest(*h, db));
  }
}
BENCHMARK(BM_GlimpseEsf)->Unit(benchmark::kMillisecond);

void BM_PclEsf(benchmark::State& state) {
  const Cloud& c = view10k();
  const auto db = stored(kEsfSize, 1);
  for (auto _ : state) {
    auto h = pcl_reference::esf(c);
    if (!h.ok()) state.SkipWithError(h.error().message.c_str());
    else benchmark::DoNotOptimize(nearest(*h, db));
  }
}
BENCHMARK(BM_PclEsf)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace glimpse

BENCHMARK_MAIN();
