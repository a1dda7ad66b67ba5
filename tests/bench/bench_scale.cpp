// Classify's latency and the model's size against the number of categories and of references per
// category (issue 56). BM_ScaleCategories/N: the same 200 zoo objects (40 of each of the zoo's five
// categories, the paper's six ideal views each, learnt whole and as top-down prefixes) dealt into N
// categories (5, 15, 50, 100; each zoo category split into N/5 groups of its objects), so only the
// categories change, not the references. BM_ScaleReferences/K: the zoo's five categories with K objects
// each (5, 10, 20, 40). Each run classifies one 10k-point view with the default method (fusion), the
// model's threads (every core); counters give the model's serialised size (MiB) and its training clouds. After the table the
// ratios of the medians are printed: 100 categories against 5 (goal <= 1.3) and 40 objects per category
// against 5. Models are trained once per size, outside the timed loop. Run with
// --benchmark_repetitions=5 --benchmark_report_aggregates_only=true.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>

#include "glimpse/learning/model.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/views/zoo.h"
#include "median_reporter.h"
#include "zoo_recipe.h"
#include "scene.h"

namespace glimpse {
namespace {

constexpr double kZooDensity = 3363.8;  // the zoo's ideal views' median density (zoo_recipe.h)

// per_category objects of each zoo category (seed 42), their ideal views, each zoo category split into
// `groups` categories "chair.0", "chair.1", ... (object i in group i % groups).
std::vector<TrainingCloud> grouped_zoo(size_t per_category, size_t groups) {
  const ViewRecipe recipe;  // the paper's six ideal views, no sensor views
  std::vector<TrainingCloud> out;
  std::map<std::string, size_t> seen;
  for (const LabelledMesh& object : make_zoo(per_category, 42)) {
    const std::string category = bench::grouped_category(object.category, seen[object.category]++, groups);
    const std::string key = object.category + "/" + object.id;
    const ObjectViews views = training_views(object.mesh, key, object.any_pose, recipe, kZooDensity);
    for (const Cloud& view : views.views)
      if (!view.points.empty()) out.push_back({category, key, view, false});
  }
  return out;
}

// One trained model per (objects per category, groups), kept for the process.
const Model* scale_model(size_t per_category, size_t groups) {
  static std::map<std::pair<size_t, size_t>, std::unique_ptr<Model>> models;
  auto& m = models[{per_category, groups}];
  if (!m) {
    auto trained = train(grouped_zoo(per_category, groups), TrainParams{});
    if (!trained.ok()) {
      std::fprintf(stderr, "training %zu per category in %zu groups: %s\n", per_category, groups,
                   trained.error().message.c_str());
      return nullptr;
    }
    m = std::make_unique<Model>(std::move(*trained));
  }
  return m.get();
}

void classify_with(benchmark::State& state, const Model* model) {
  if (!model) {
    state.SkipWithError("training failed");
    return;
  }
  const Cloud& view = bench::view10k();
  for (auto _ : state) {
    auto c = classify(*model, view);
    if (!c.ok()) {
      state.SkipWithError(c.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(c);
  }
  state.counters["categories"] = static_cast<double>(model->categories.size());
  state.counters["clouds"] = static_cast<double>(model->stats.clouds);
  state.counters["MiB"] = static_cast<double>(serialize(*model).size()) / (1024.0 * 1024.0);
}

void BM_ScaleCategories(benchmark::State& state) {
  classify_with(state, scale_model(40, static_cast<size_t>(state.range(0)) / 5));
}
BENCHMARK(BM_ScaleCategories)->Arg(5)->Arg(15)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ScaleReferences(benchmark::State& state) {
  classify_with(state, scale_model(static_cast<size_t>(state.range(0)), 1));
}
BENCHMARK(BM_ScaleReferences)->Arg(5)->Arg(10)->Arg(20)->Arg(40)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace glimpse

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  glimpse::bench::MedianReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  if (const double r = reporter.ratio("BM_ScaleCategories/100", "BM_ScaleCategories/5"); r > 0)
    std::printf("classify at 100 categories / at 5 (the same references): %.2f (goal <= 1.3)\n", r);
  if (const double r = reporter.ratio("BM_ScaleReferences/40", "BM_ScaleReferences/5"); r > 0)
    std::printf("classify at 40 objects per category / at 5 (five categories): %.2f\n", r);
  benchmark::Shutdown();
  return 0;
}
