// Accuracy, confusion and the category changes of the exploration (sec. 4).
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <tuple>

#include "glimpse/evaluation.h"
#include "random.h"

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

void add_ablation(EvalResult& result, const EvalResult& other, const std::string& label, const std::string& group) {
  for (MethodId m : other.params.methods) {
    AblationRow row;
    row.group = group;
    row.label = label;
    row.method = m;
    for (const Stage& s : result.params.stages) {
      const std::string name = stage_name(s);
      const Tally t = accuracy(other.decisions, name, m);
      row.accuracy.push_back(t.total ? t.percent() : -1.0);
      row.balanced.push_back(t.total ? balanced_accuracy(other.decisions, name, m, other.categories.size()) : -1.0);
    }
    result.ablations.push_back(std::move(row));
  }
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

size_t category_changes(std::span<const int> winners) {
  size_t changes = 0;
  for (size_t i = 1; i < winners.size(); ++i) changes += winners[i] != winners[i - 1];
  return changes;
}

std::vector<ExplorationTrace> exploration_traces(std::span<const StageDecision> decisions, MethodId method,
                                                 const std::vector<size_t>& grid) {
  std::map<std::string, size_t> grid_index;
  for (size_t g = 0; g < grid.size(); ++g)
    grid_index.emplace(stage_name({StageKind::kKeypoints, double(grid[g])}), g);
  struct Partial {
    ExplorationTrace trace;
    std::vector<char> seen;
    bool has_full = false;
  };
  std::map<std::tuple<int, int, int>, Partial> views;  // (fold, object, view), so traces come out ordered
  for (const StageDecision& d : decisions) {
    if (d.method != method || d.truth < 0) continue;
    const bool full = d.stage == "full";
    auto g = grid_index.find(d.stage);
    if (!full && g == grid_index.end()) continue;
    Partial& p = views[{d.fold, d.object, d.view}];
    if (p.seen.empty()) {
      p.trace.fold = d.fold, p.trace.object = d.object, p.trace.view = d.view, p.trace.truth = d.truth;
      p.trace.grid = grid;
      p.trace.winners.assign(grid.size(), -1);
      p.trace.visible_fraction.assign(grid.size(), 0.0);
      p.seen.assign(grid.size(), 0);
    }
    if (full) {
      p.has_full = true;
      p.trace.final_winner = d.winner;
      p.trace.full_visible_fraction = d.visible_fraction;
    }
    if (g != grid_index.end()) {
      p.trace.winners[g->second] = d.winner;
      p.trace.visible_fraction[g->second] = d.visible_fraction;
      p.seen[g->second] = 1;
    }
  }
  std::vector<ExplorationTrace> out;
  for (auto& [key, p] : views) {
    if (!p.has_full) continue;
    // Keep only the grid stages that were decided (a protocol without some of them still gives traces).
    ExplorationTrace t = p.trace;
    t.grid.clear(), t.winners.clear(), t.visible_fraction.clear();
    for (size_t g = 0; g < grid.size(); ++g)
      if (p.seen[g]) {
        t.grid.push_back(grid[g]);
        t.winners.push_back(p.trace.winners[g]);
        t.visible_fraction.push_back(p.trace.visible_fraction[g]);
      }
    out.push_back(std::move(t));
  }
  return out;
}

std::vector<ChangeRow> change_summary(const std::vector<ExplorationTrace>& traces,
                                      const std::vector<size_t>& up_to) {
  std::vector<ChangeRow> rows;
  for (size_t limit : up_to) {
    ChangeRow row;
    row.up_to_keypoints = limit;
    double sum_c = 0, sum_i = 0;
    for (const ExplorationTrace& t : traces) {
      std::vector<int> seq;
      for (size_t g = 0; g < t.grid.size(); ++g)
        if (t.grid[g] <= limit) seq.push_back(t.winners[g]);
      const double c = double(category_changes(seq));
      if (t.correct()) sum_c += c, ++row.views_correct;
      else sum_i += c, ++row.views_incorrect;
    }
    row.mean_correct = row.views_correct ? sum_c / double(row.views_correct) : 0.0;
    row.mean_incorrect = row.views_incorrect ? sum_i / double(row.views_incorrect) : 0.0;
    rows.push_back(row);
  }
  return rows;
}

}  // namespace glimpse
