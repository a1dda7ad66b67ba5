// Classify of a 20k-point depth camera view with a model trained by the recipe (the zoo's 5 objects
// per category, the paper's ideal views and the training cameras', the default methods): issue 55's goal
// is a median of at most 15 ms on a 2-core VM. BM_ClassifyDepthView/<arm>: arm 0 a zoo chair of
// another seed seen by the depth camera at 1.5 m, 15 degrees up, thinned evenly to 20,000 points; arm 1
// the same chair on a floor, 20,000 points of chair and floor (the scan filters' RANSAC plane); the
// baseline, run first in the same process, is the same chair's ideal view (HPR, about 2,000 points, what
// the model was trained on). After the table the medians and their ratios to the baseline are printed
// beside the goal. Every run uses every core.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "zoo_recipe.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/scan_conditions.h"

namespace glimpse {
namespace {

const Model* recipe_model() {
  static const std::unique_ptr<Model> m = [] {
    auto trained = train(bench::zoo_training_set(5), TrainParams{});
    return trained.ok() ? std::make_unique<Model>(std::move(*trained)) : nullptr;
  }();
  return m.get();
}

const LabelledMesh& chair() {
  static const LabelledMesh c = [] {
    for (LabelledMesh& m : make_zoo(1, 7))
      if (m.category == "chair") return m;
    return LabelledMesh{};
  }();
  return c;
}

// Every k-th point of `cloud` so that exactly `target` remain (all of them when it has fewer).
Cloud thinned_to(const Cloud& cloud, size_t target) {
  if (cloud.points.size() <= target) return cloud;
  Cloud out{{}, cloud.sensor, cloud.frame};
  const double step = double(cloud.points.size()) / double(target);
  for (size_t i = 0; i < target; ++i) out.points.push_back(cloud.points[size_t(double(i) * step)]);
  return out;
}

// Arm -1: the ideal view; 0: the depth camera's view; 1: the same on a floor.
const Cloud& view(int arm) {
  static std::map<int, Cloud> views;
  if (auto it = views.find(arm); it != views.end()) return it->second;
  const LabelledMesh& c = chair();
  const uint64_t seed = object_seed(7, "chair/bench");
  Cloud v;
  if (arm < 0) {
    v = training_views(c.mesh, "chair/bench", false, ViewRecipe{}, 3363.8).views.front();
  } else {
    ScanCondition depth;
    depth.sensor = SensorKind::kDepthCamera, depth.distance_m = 1.5f, depth.elevation_deg = 15.f, depth.floor = arm == 1;
    v = thinned_to(condition_view(c.mesh, false, {}, 0, 6, seed, depth, 6000, 100), 20000);
  }
  return views[arm] = std::move(v);
}

std::map<int, double>& medians() {
  static std::map<int, double> m;
  return m;
}

void classify_arm(benchmark::State& state, int arm) {
  const Model* m = recipe_model();
  if (!m || chair().mesh.vertices.empty()) {
    state.SkipWithError("training or the zoo's chair failed");
    return;
  }
  const Cloud& cloud = view(arm);
  std::vector<double> times;
  size_t kept = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto r = classify(*m, cloud);
    if (!r.ok()) {
      state.SkipWithError(r.error().message.c_str());
      return;
    }
    kept = r->points;
    benchmark::DoNotOptimize(r->winner);
    times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::nth_element(times.begin(), times.begin() + std::ptrdiff_t(times.size() / 2), times.end());
  medians()[arm] = times[times.size() / 2];
  state.counters["points_sent"] = double(cloud.points.size());
  state.counters["points_kept"] = double(kept);
}

void BM_ClassifyIdealView(benchmark::State& state) { classify_arm(state, -1); }
BENCHMARK(BM_ClassifyIdealView)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_ClassifyDepthView(benchmark::State& state) { classify_arm(state, int(state.range(0))); }
BENCHMARK(BM_ClassifyDepthView)->DenseRange(0, 1)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
}  // namespace glimpse

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  const auto& m = glimpse::medians();
  const auto ideal = m.find(-1);
  for (int arm : {0, 1}) {
    const auto it = m.find(arm);
    if (it == m.end() || ideal == m.end() || ideal->second <= 0) continue;
    std::printf("Classify, 20k-point depth view%s: median %.2f ms (goal <= 15 ms), %.2fx the ideal view's %.2f ms\n",
                arm ? " on a floor" : "", it->second, it->second / ideal->second, ideal->second);
  }
  benchmark::Shutdown();
  return 0;
}
