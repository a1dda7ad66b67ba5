// Cost of making the paper's single views: hidden point removal (Katz 2007) and surface sampling.
#include <benchmark/benchmark.h>

#include "glimpse/views/sampling.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/zoo.h"

namespace {

glimpse::Points zoo_points(int64_t n) {
  glimpse::Expected<glimpse::Mesh> m = glimpse::make_zoo_shape("chair", 1);
  const double area = glimpse::surface_area(*m);
  return glimpse::sample_surface(*m, double(n) / area, 7).points;
}

void BM_HiddenPointRemoval(benchmark::State& state) {
  const glimpse::Points pts = zoo_points(state.range(0));
  const glimpse::Vec3 camera = glimpse::paper_viewpoints(pts).front();
  for (auto _ : state) benchmark::DoNotOptimize(glimpse::hidden_point_removal(pts, camera));
  state.SetItemsProcessed(state.iterations() * int64_t(pts.size()));
}
BENCHMARK(BM_HiddenPointRemoval)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_SampleSurface(benchmark::State& state) {
  const glimpse::Expected<glimpse::Mesh> m = glimpse::make_zoo_shape("human", 1);
  const double density = double(state.range(0)) / glimpse::surface_area(*m);
  for (auto _ : state) benchmark::DoNotOptimize(glimpse::sample_surface(*m, density, 3));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_SampleSurface)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

void BM_MakeZooShape(benchmark::State& state) {
  uint64_t seed = 0;
  for (auto _ : state) benchmark::DoNotOptimize(glimpse::make_zoo_shape("fourleg", seed++));
}
BENCHMARK(BM_MakeZooShape)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
