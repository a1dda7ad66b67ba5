// Training's cost against the size of the training set: train() of the zoo's objects with the recipe's
// views (the paper's six ideal views and the two training cameras' six, every view learnt whole and as
// five top-down prefixes), the default methods, on every core. BM_Train/N: N objects per category (5
// categories); the goal is that 4 times the objects take at most 4.4 times as long (issue 55), the ratio
// printed at the end from the medians. BM_Train/N/0 is the baseline run in the same process: calibration
// decides every held-out row (TrainParams::calibration_queries 0), quadratic in the rows. The views are
// made once, outside the timed loop; features, stages, the logistic decision, calibration and the
// novelty model are timed.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>

#include "glimpse/learning/model.h"
#include "glimpse/learning/train_params.h"
#include "median_reporter.h"
#include "zoo_recipe.h"

namespace glimpse {
namespace {

void BM_Train(benchmark::State& state) {
  const std::vector<TrainingCloud> data = bench::zoo_training_set(static_cast<size_t>(state.range(0)));
  TrainParams params;
  if (state.range(1) == 0) params.calibration_queries = 0;
  size_t rows = 0;
  for (auto _ : state) {
    auto model = train(data, params);
    if (!model.ok()) {
      state.SkipWithError(model.error().message.c_str());
      return;
    }
    rows = model->stats.clouds;
    benchmark::DoNotOptimize(model);
  }
  state.counters["clouds"] = static_cast<double>(rows);
}
BENCHMARK(BM_Train)->ArgsProduct({{5, 20}, {1, 0}})->Iterations(1)->Repetitions(3)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace glimpse

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  glimpse::bench::MedianReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  for (const std::string capped : {"1", "0"}) {
    const std::string small = "BM_Train/5/" + capped, large = "BM_Train/20/" + capped;
    const double ratio = reporter.ratio(large, small);
    if (!(ratio > 0)) continue;
    std::printf("training%s: 20 objects per category %.1f s, 5 per category %.1f s: ratio %.2f for 4x the objects%s\n",
                capped == "1" ? "" : ", every held-out row decided", reporter.medians.at(large), reporter.medians.at(small),
                ratio, capped == "1" ? " (goal <= 4.4)" : "");
  }
  benchmark::Shutdown();
  return 0;
}
