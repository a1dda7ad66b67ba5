// The report's ablation sections: how much is size (the size-only method and the size-blind rows),
// keypoints and visible fraction per view, and the keypoint ablation (report.cpp puts them in order).
#include <algorithm>
#include <sstream>
#include <string>

#include "report_format.h"
#include "protocol.h"
#include "glimpse/lab/evaluation.h"
#include "glimpse/learning/model_internals.h"

namespace glimpse {

std::string keypoint_summary(const EvalResult& r) {
  using eval_internal::pct;
  const size_t tested = eval_internal::tested_views(r);
  std::string out;
  for (const StageStats& st : r.stage_stats) {
    if (st.stage == "full") out = "full views " + pct(st.mean_keypoints, 1) + " kp";
    if (st.stage == "25kp" && tested)
      out += (out.empty() ? "" : ", ") + pct(100.0 * double(st.cut_views) / double(tested), 1) + " % >= 25";
  }
  return out;
}

namespace eval_internal {

std::string size_section(const EvalResult& r) {
  std::ostringstream o;
  const bool size_method = std::find(r.params.methods.begin(), r.params.methods.end(), MethodId::kSize) != r.params.methods.end();
  const bool size_rows = std::any_of(r.ablations.begin(), r.ablations.end(), [](const AblationRow& a) { return a.group == "size"; });
  if (!size_method && !size_rows) return {};
  const std::vector<std::string> stages = main_stage_names(r);
  o << "## How much is size\n\n";
  o << "Objects are scaled to real-life sizes, and the category ranges barely overlap (human 1.55-1.95 m tall, chair "
       "0.80-1.10, table 0.70-0.80, parts at most 0.40 m across), so size alone tells much. **Size only** decides from "
       "the visible height and the two horizontal extents of the (partial) cloud, nothing else, with the same decision "
       "stage. The **size-blind** rows repeat the evaluation with every object scaled to the same height (1 m), for "
       "training and test alike: what is left is shape.\n\n| method | accuracy: ";
  for (size_t i = 0; i < stages.size(); ++i) o << (i ? " | " : "") << stages[i];
  o << " | balanced: ";
  for (size_t i = 0; i < stages.size(); ++i) o << (i ? " | " : "") << stages[i];
  o << " |\n|---|";
  for (size_t i = 0; i < 2 * stages.size(); ++i) o << "---:|";
  o << "\n";
  auto real_row = [&](MethodId m) {
    o << "| " << method_label(m) << " |";
    for (const std::string& s : stages) o << " " << pct(accuracy(r.decisions, s, m).percent(), 1) << " |";
    for (const std::string& s : stages) o << " " << pct(balanced_accuracy(r.decisions, s, m, r.categories.size()), 1) << " |";
    o << "\n";
  };
  if (size_method) real_row(MethodId::kSize);
  for (const AblationRow& a : r.ablations) {
    if (a.group != "size") continue;
    if (std::find(r.params.methods.begin(), r.params.methods.end(), a.method) != r.params.methods.end()) real_row(a.method);
    o << "| " << method_label(a.method) << ", " << a.label << " |";
    for (double v : a.accuracy) o << " " << (v < 0 ? "–" : pct(v, 1)) << " |";
    for (double v : a.balanced) o << " " << (v < 0 ? "–" : pct(v, 1)) << " |";
    o << "\n";
  }
  o << "\n";
  return o.str();
}

std::string keypoint_ablation_section(const EvalResult& r) {
  std::ostringstream o;
  if (std::none_of(r.ablations.begin(), r.ablations.end(), [](const AblationRow& a) { return a.group == "keypoints"; }))
    return {};
  const std::vector<std::string> stages = main_stage_names(r);
  o << "## Keypoint ablation\n\nThe keypoint methods re-run with one setting changed at a time from this run's (first rows), "
       "everything else equal (same views, folds, seeds; no streams). Each setting says what its full views held: mean "
       "keypoints, and the share of tested views with at least 25 (the paper's 25 kp stage is real only there).\n\n"
       "| setting | method |";
  for (const std::string& s : stages) o << " " << s << " |";
  o << "\n|---|---|";
  for (size_t i = 0; i < stages.size(); ++i) o << "---:|";
  o << "\n";
  const std::string mine = keypoint_summary(r);
  bool first = true;
  for (MethodId m : r.params.methods) {
    if (!uses_keypoints(m)) continue;
    o << "| " << (first ? "**this run** (" + mine + ")" : std::string()) << " | " << method_label(m) << " |";
    first = false;
    for (const std::string& s : stages) o << " " << pct(accuracy(r.decisions, s, m).percent(), 1) << " |";
    o << "\n";
  }
  std::string last;
  for (const AblationRow& a : r.ablations) {
    if (a.group != "keypoints") continue;
    o << "| " << (a.label == last ? std::string() : a.label) << " | " << method_label(a.method) << " |";
    last = a.label;
    for (double v : a.accuracy) o << " " << (v < 0 ? "–" : pct(v, 1)) << " |";
    o << "\n";
  }
  o << "\n";
  return o.str();
}

std::string keypoints_section(const EvalResult& r) {
  std::ostringstream o;
  o << "## Keypoints and visible fraction per view, by category and stage\n\n";
  o << "Mean over all views (every fold's test views are all views). `kp` = keypoints found on the stage's prefix, "
       "`vis` = prefix points / full 3D cloud points (%). Exploration-grid stages follow the main ones.\n\n";
  o << "| stage |";
  for (const std::string& c : r.categories) o << " " << c << " kp | " << c << " vis |";
  o << " all kp | all vis | failed | feature CPU s |\n|---|";
  for (size_t i = 0; i < r.categories.size(); ++i) o << "---:|---:|";
  o << "---:|---:|---:|---:|\n";
  for (const StageStats& st : r.stage_stats) {
    size_t failed = 0;
    for (size_t f : st.failed) failed += f;
    o << "| " << st.stage << " |";
    for (size_t c = 0; c < r.categories.size(); ++c)
      o << " " << pct(st.keypoints[c], 1) << " | " << pct(st.visible_percent[c], 1) << " |";
    o << " " << pct(st.mean_keypoints, 1) << " | " << pct(st.mean_visible_percent, 1) << " | " << failed << " | "
      << fmt("%.1f", st.feature_seconds) << " |\n";
  }
  o << "\nKeypoint stage cuts, over the views whose full view has at least k keypoints (elsewhere the stage is the "
       "whole view): keypoints re-extraction finds on the prefix cut below the k-th highest full-view keypoint.\n\n"
       "| stage | views with >= k keypoints | % of tested views | prefix keypoints mean (min-max) | visible % |\n"
       "|---|---:|---:|---:|---:|\n";
  const size_t tested = tested_views(r);
  for (const StageStats& st : r.stage_stats) {
    if (st.stage.size() < 3 || st.stage.substr(st.stage.size() - 2) != "kp") continue;
    o << "| " << st.stage << " | " << st.cut_views << " | "
      << (tested ? pct(100.0 * double(st.cut_views) / double(tested), 1) : std::string("–")) << " | ";
    if (st.cut_views)
      o << pct(st.cut_mean_keypoints, 1) << " (" << st.cut_min_keypoints << "-" << st.cut_max_keypoints << ") | "
        << pct(st.cut_visible_percent, 1) << " |\n";
    else
      o << "– | – |\n";
  }
  o << "\n";
  return o.str();
}

}  // namespace eval_internal
}  // namespace glimpse
