// Per-stage cost of feature extraction on a 10k-point single view, against the floor: one radius-
// neighbourhood pass over the cloud (every point's neighbourhood must be visited at least once).
// Goal (issue 3): the whole extraction within 2x that pass. Compare the medians in the same run.
// Measured (2-core VM, medians of 5): floor 9.4 ms; local surfaces 22.0 ms (1 thread) / 12.0 (2);
// extract 30.9 ms (1 thread) = 3.3x the floor, 19.9 ms (2 threads) = 2.1x. Not within 2x on one
// thread: the quadric fit per neighbourhood costs about 1.3 passes on its own.
#include <benchmark/benchmark.h>

#include "scene.h"
#include "glimpse/features.h"
#include "glimpse/geometry.h"

namespace glimpse {
namespace {

using bench::view10k;

void BM_RadiusPassFloor(benchmark::State& state) {
  const Cloud& c = view10k();
  const KdTree tree(c.points);
  const float r = support_radius(tree, {});
  std::vector<Neighbour> nb;
  for (auto _ : state) {
    size_t total = 0;
    for (const Vec3& p : c.points) {
      tree.radius(p, r, nb);
      total += nb.size();
    }
    benchmark::DoNotOptimize(total);
  }
  state.counters["points"] = static_cast<double>(c.points.size());
}
BENCHMARK(BM_RadiusPassFloor)->Unit(benchmark::kMillisecond);

void BM_LocalSurfaces(benchmark::State& state) {
  const Cloud& c = view10k();
  const KdTree tree(c.points);
  SurfaceParams params;
  params.threads = static_cast<int>(state.range(0));
  const float r = support_radius(tree, params);
  for (auto _ : state) benchmark::DoNotOptimize(local_surfaces(tree, r, c.sensor, params));
}
BENCHMARK(BM_LocalSurfaces)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_Extract(benchmark::State& state) {
  const Cloud& c = view10k();
  FeatureParams params;
  params.surface.threads = static_cast<int>(state.range(0));
  size_t keypoints = 0;
  double surf = 0, kp = 0, desc = 0;
  for (auto _ : state) {
    auto f = extract(c, params);
    if (!f.ok()) state.SkipWithError(f.error().message.c_str());
    keypoints = f->keypoints.size();
    surf += f->diagnostics.surfaces_ms, kp += f->diagnostics.keypoints_ms, desc += f->diagnostics.descriptors_ms;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["keypoints"] = static_cast<double>(keypoints);
  state.counters["surfaces_ms"] = surf / n;
  state.counters["keypoints_ms"] = kp / n;
  state.counters["descriptors_ms"] = desc / n;
}
BENCHMARK(BM_Extract)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace glimpse

BENCHMARK_MAIN();
