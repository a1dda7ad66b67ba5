// The category changes of the exploration (sec. 4) and the ablation rows.
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <tuple>

#include "glimpse/lab/evaluation.h"
#include "glimpse/random.h"

namespace glimpse {

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
