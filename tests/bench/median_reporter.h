// The console reporter that also keeps each benchmark's median (or its single run, without
// repetitions), keyed "function/args" ("BM_Train/20/1"), for the ratios a bench prints after its table.
#pragma once

#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <vector>

namespace glimpse::bench {

class MedianReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      const bool single = r.run_type == Run::RT_Iteration && r.repetitions <= 1;
      if (!r.error_occurred && (median || single)) medians[r.run_name.function_name + "/" + r.run_name.args] = r.GetAdjustedRealTime();
    }
    ConsoleReporter::ReportRuns(runs);
  }
  // large's median over small's; 0 when either is missing or small's is not positive.
  double ratio(const std::string& large, const std::string& small) const {
    const auto a = medians.find(large), b = medians.find(small);
    return a == medians.end() || b == medians.end() || !(b->second > 0) ? 0.0 : a->second / b->second;
  }
  std::map<std::string, double> medians;  // in the benchmark's time unit
};

}  // namespace glimpse::bench
