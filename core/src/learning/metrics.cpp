// Accuracy, balanced accuracy, confusion and how far they could move with other test objects.
#include "glimpse/learning/metrics.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <tuple>

#include "glimpse/random.h"

namespace glimpse {

Tally accuracy(std::span<const StageDecision> decisions, std::string_view stage, MethodId method) {
  Tally t;
  for (const StageDecision& d : decisions) {
    if (d.method != method || d.stage != stage || d.truth < 0) continue;
    ++t.total;
    t.correct += d.winner == d.truth;
  }
  return t;
}

double balanced_accuracy(std::span<const StageDecision> decisions, std::string_view stage, MethodId method,
                         size_t categories) {
  std::vector<Tally> per(categories);
  for (const StageDecision& d : decisions) {
    if (d.method != method || d.stage != stage || d.truth < 0 || static_cast<size_t>(d.truth) >= categories) continue;
    ++per[d.truth].total;
    per[d.truth].correct += d.winner == d.truth;
  }
  double sum = 0;
  size_t n = 0;
  for (const Tally& t : per)
    if (t.total) sum += t.percent(), ++n;
  return n ? sum / double(n) : 0.0;
}

namespace {
// The percentile interval holding `level` of `draws` values of statistic(picks), each picks `units`
// indices into [0, units) drawn with replacement (a bootstrap over units). The same seed, the same interval.
AccuracyInterval percentile_bootstrap(size_t units, double level, size_t draws, uint64_t seed,
                                      const std::function<double(const std::vector<size_t>&)>& statistic) {
  if (units == 0 || draws == 0) return {};
  std::mt19937_64 rng(seed);
  std::vector<double> resampled(draws);
  std::vector<size_t> picks(units);
  for (double& value : resampled) {
    for (size_t& i : picks) i = std::min(units - 1, static_cast<size_t>(uniform01(rng) * double(units)));
    value = statistic(picks);
  }
  std::sort(resampled.begin(), resampled.end());
  const double tail = std::clamp((1.0 - level) / 2.0, 0.0, 0.5);
  auto at = [&](double q) { return resampled[std::min(draws - 1, static_cast<size_t>(q * double(draws)))]; };
  return {at(tail), at(1.0 - tail)};
}
}  // namespace

AccuracyInterval accuracy_interval(std::span<const StageDecision> decisions, std::string_view stage, MethodId method,
                                   double level, size_t draws, uint64_t seed) {
  std::map<int, Tally> per_object;
  for (const StageDecision& d : decisions) {
    if (d.method != method || d.stage != stage || d.truth < 0) continue;
    Tally& t = per_object[d.object];
    ++t.total;
    t.correct += d.winner == d.truth;
  }
  std::vector<Tally> objects;
  for (const auto& [object, t] : per_object) objects.push_back(t);
  return percentile_bootstrap(objects.size(), level, draws, seed, [&](const std::vector<size_t>& picks) {
    Tally sum;
    for (size_t i : picks) sum.correct += objects[i].correct, sum.total += objects[i].total;
    return sum.percent();
  });
}

PairedDifference paired_difference(std::span<const PairedView> views, double level, size_t draws, uint64_t seed) {
  struct Unit {
    size_t views = 0, before = 0, after = 0;
  };
  std::map<int, Unit> per_unit;
  PairedDifference out;
  for (const PairedView& v : views) {
    Unit& u = per_unit[v.unit];
    ++u.views;
    u.before += v.right_before;
    u.after += v.right_after;
    out.turned_right += !v.right_before && v.right_after;
    out.turned_wrong += v.right_before && !v.right_after;
  }
  if (per_unit.empty()) return out;
  std::vector<Unit> units;
  Unit all;
  for (const auto& [id, u] : per_unit) {
    units.push_back(u);
    all.views += u.views, all.before += u.before, all.after += u.after;
  }
  auto points = [](size_t right, size_t of) { return 100.0 * double(right) / double(of); };
  out.views = all.views;
  out.units = units.size();
  out.before = points(all.before, all.views);
  out.after = points(all.after, all.views);
  out.difference = out.after - out.before;
  out.interval = percentile_bootstrap(units.size(), level, draws, seed, [&](const std::vector<size_t>& picks) {
    Unit sum;
    for (size_t i : picks) sum.views += units[i].views, sum.before += units[i].before, sum.after += units[i].after;
    return points(sum.after, sum.views) - points(sum.before, sum.views);
  });
  return out;
}

std::vector<std::vector<double>> confusion_percent(std::span<const StageDecision> decisions, std::string_view stage,
                                                   MethodId method, size_t categories) {
  std::vector<std::vector<double>> m(categories, std::vector<double>(categories, 0.0));
  std::vector<size_t> row_total(categories, 0);
  for (const StageDecision& d : decisions) {
    if (d.method != method || d.stage != stage) continue;
    if (d.truth < 0 || static_cast<size_t>(d.truth) >= categories) continue;
    ++row_total[d.truth];
    if (d.winner >= 0 && static_cast<size_t>(d.winner) < categories) m[d.truth][d.winner] += 1;
  }
  for (size_t r = 0; r < categories; ++r)
    if (row_total[r])
      for (double& v : m[r]) v *= 100.0 / double(row_total[r]);
  return m;
}

double auroc(std::vector<double> negatives, std::vector<double> positives) {
  if (negatives.empty() || positives.empty()) return 0.5;
  std::sort(negatives.begin(), negatives.end());
  double wins = 0;
  for (double p : positives) {
    const auto lo = std::lower_bound(negatives.begin(), negatives.end(), p);
    const auto hi = std::upper_bound(negatives.begin(), negatives.end(), p);
    wins += double(lo - negatives.begin()) + 0.5 * double(hi - lo);
  }
  return wins / (double(negatives.size()) * double(positives.size()));
}

}  // namespace glimpse
