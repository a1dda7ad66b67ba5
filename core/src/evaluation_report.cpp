// The evaluation report a person reads: the markdown sections in the order they appear (the CSV, SVG and
// terminal writers and the report folder are evaluation_writers.cpp's).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "glimpse/evaluation.h"
#include "evaluation_format.h"
#include "evaluation_internal.h"
#include "model_impl.h"

namespace glimpse {

namespace {

using namespace eval_internal;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

const char* paper_category_label(const std::string& c) {
  if (c == "human") return "Human";
  if (c == "chair") return "Chair";
  if (c == "table") return "Table";
  if (c == "mechanic") return "Angular machine part";
  if (c == "fourleg") return "Quadruped";
  return nullptr;
}

// Paper Tables 1-3, the diagonal (correct %) per category (human, chair, table, mechanic, fourleg)
// for VFH, KGH, BoK, BoG.
struct PaperDiagonal {
  const char* stage;
  std::array<std::array<double, 4>, 5> rate;  // [category][method]
};
constexpr PaperDiagonal kPaperTables[] = {
    {"full", {{{28, 82, 88, 67}, {89, 100, 100, 94}, {22, 72, 67, 67}, {83, 94, 100, 94}, {100, 94, 89, 94}}}},
    {"10kp", {{{61, 0, 56, 67}, {83, 72, 94, 72}, {17, 89, 17, 33}, {61, 0, 89, 89}, {61, 0, 67, 11}}}},
    {"25kp", {{{56, 0, 39, 61}, {89, 100, 94, 89}, {16, 72, 28, 50}, {67, 50, 89, 78}, {78, 0, 89, 50}}}},
};

int paper_method_column(MethodId m) {
  switch (m) {
    case MethodId::kVFH: return 0;
    case MethodId::kKGH: return 1;
    case MethodId::kBoK: return 2;
    case MethodId::kBoG: return 3;
    default: return -1;
  }
}

double paper_diagonal(std::string_view stage, const std::string& category, MethodId m) {
  static const char* const kOrder[] = {"human", "chair", "table", "mechanic", "fourleg"};
  const int col = paper_method_column(m);
  if (col < 0) return kNaN;
  for (const PaperDiagonal& t : kPaperTables) {
    if (stage != t.stage) continue;
    for (int c = 0; c < 5; ++c)
      if (category == kOrder[c]) return t.rate[c][col];
  }
  return kNaN;
}

std::string join_methods(const std::vector<MethodId>& ms) {
  std::string s;
  for (MethodId m : ms) s += (s.empty() ? "" : ", ") + std::string(method_name(m));
  return s;
}

void write_protocol(std::ostringstream& o, const EvalResult& r) {
  const EvalParams& p = r.params;
  size_t min_pts = std::numeric_limits<size_t>::max(), max_pts = 0;
  double mean_pts = 0;
  for (size_t n : r.object_points) min_pts = std::min(min_pts, n), max_pts = std::max(max_pts, n), mean_pts += double(n);
  if (!r.object_points.empty()) mean_pts /= double(r.object_points.size());
  std::map<std::string, size_t> per_cat;
  for (int t : r.object_truth)
    if (t >= 0) ++per_cat[r.categories[static_cast<size_t>(t)]];
  std::string cats;
  for (const std::string& c : r.categories) cats += (cats.empty() ? "" : ", ") + c + " " + std::to_string(per_cat[c]);

  o << "## Protocol\n\n| parameter | ours | paper |\n|---|---|---|\n";
  o << "| data | " << r.source << " (" << r.object_ids.size() << " objects: " << cats << ") | SHREC 2007, same 5 categories, 20 objects each |\n";
  if (r.cross_source) {
    auto count = [&](bool tested) {
      std::map<std::string, size_t> n;
      for (size_t i = 0; i < r.object_fold.size(); ++i)
        if ((r.object_fold[i] >= 0) == tested && r.object_truth[i] >= 0)
          ++n[r.categories[static_cast<size_t>(r.object_truth[i])]];
      std::string s;
      for (const auto& [c, k] : n) s += (s.empty() ? "" : ", ") + c + " " + std::to_string(k);
      return s;
    };
    std::string train, test;
    for (const std::string& x : r.train_sources) train += (train.empty() ? "" : ", ") + x;
    for (const std::string& x : r.test_sources) test += (test.empty() ? "" : ", ") + x;
    o << "| cross-source | one model trained on every object of **" << train << "** (" << count(false)
      << "), tested on every view of **" << test << "** (" << count(true)
      << "); nothing of the test collections is learnt or calibrated on | – |\n";
  }
  o << "| object cloud (`--points`) | "
    << (p.points_per_object ? std::to_string(p.points_per_object) +
                                  " area-weighted surface samples per object (seeded): a sensor at 3x the bounding radius "
                                  "sees about as many points whatever the object's size, and vertex counts (which vary "
                                  "10x across meshes) would hint at the category"
                            : std::string("mesh vertices"))
    << "; " << min_pts << " / " << std::lround(mean_pts) << " / " << max_pts << " points (min / mean / max) | mesh vertices |\n";
  o << "| views per object | " << p.views_per_object << ", HPR (Katz 2007, radius factor " << p.hpr_radius_factor
    << "), azimuth every " << 360 / std::max<size_t>(1, std::min<size_t>(6, p.views_per_object))
    << " deg, elevation 30 deg, 3x bounding radius";
  if (!r.any_pose_categories.empty()) {
    o << "; objects of categories without a natural up (";
    for (size_t i = 0; i < r.any_pose_categories.size(); ++i) o << (i ? ", " : "") << r.any_pose_categories[i];
    o << ") turned to a random pose (seeded) for each view, training and test alike";
  }
  o << " | 6, HPR |\n";
  std::string stages;
  for (const Stage& s : p.stages) stages += (stages.empty() ? "" : ", ") + stage_name(s);
  o << "| stages | " << stages << " | 10 kp (~10 %), 25 kp (~20 %), 55 kp, full view |\n";
  o << "| keypoint stage cut | keypoints of the full view sorted by height; prefix = points above the k-th highest minus "
    << p.cut_margin_supports << " support radii; features re-extracted on that prefix | prefix with k visible keypoints |\n";
  o << "| fraction stages | top prefix holding the fraction of the FULL 3D cloud's point count | ~10 %, ~20 % visible |\n";
  if (!r.cross_source)
    o << "| cross-validation | " << p.folds << "-fold by object, stratified by category, seed " << p.seed
      << "; accuracy pooled over folds | not stated |\n";
  const std::vector<double>& prefixes = p.train.partial_prefixes;
  std::string trained_on = "full views only";
  if (!prefixes.empty()) {
    trained_on = "full views + top-down prefixes holding ";
    for (size_t i = 0; i < prefixes.size(); ++i) trained_on += (i ? ", " : "") + pct(100 * prefixes[i]) + " %";
    trained_on += " of each training view";
  }
  if (p.train.tilt_deg > 0)
    trained_on += "; each training view (and its prefixes) turned by a random tilt of up to " + pct(p.train.tilt_deg) +
                  " deg (seeded), test views as seen";
  {
    std::map<std::string, size_t> extra;
    if (!r.cross_source)
      for (size_t i = 0; i < r.object_fold.size(); ++i)
        if (r.object_fold[i] < 0) ++extra[r.object_source[i]];
    for (const auto& [source, n] : extra)
      trained_on += "; plus every object of " + source + " (" + std::to_string(n) + ", training only, never tested)";
  }
  o << "| training clouds (`--train-on`, `--train-prefixes`) | " << trained_on
    << " | full views |\n";
  const TrainParams& t = p.train;
  o << "| methods | " << join_methods(p.methods) << " (fusion = mean scores of " << join_methods(t.fusion_of)
    << ") | VFH, KGH, BoK, BoG |\n";
  o << "| codebooks | BoK " << t.bok_clusters << ", BoG " << t.bog_keypoint_clusters << "x" << t.bog_volume_clusters
    << " -> " << t.bog_pca_dims << " dims, KGH " << t.kgh_clusters << "x" << t.kgh_distance_bins
    << (t.normalise_up_to_keypoints > 0
            ? ", histograms divided by their count up to " + std::to_string(t.normalise_up_to_keypoints) +
                  " keypoints and by that many's after"
            : t.normalise_histograms ? ", histograms normalised" : "")
    << " | BoK 60, BoG 6x5 -> 65, KGH 8x15; normalised early in the exploration, not later |\n";
  const KeypointParams& kp = t.features.keypoints;
  const SurfaceParams& sp = t.features.surface;
  o << "| keypoints | r = median distance to the " << sp.support_neighbours << "th nearest neighbour (surfaces need "
    << sp.min_neighbours << " within r); "
    << (kp.response == KeypointResponse::kHarris ? "ranked by the Harris response det - 0.04 tr^2 (window r/2), its "
                                                   "local maxima within r"
                                                 : "ranked by the smaller principal Harris curvature")
    << "; rho1 "
    << (kp.max_characteristic_radius_m > 0 ? "<= " + fmt("%g", double(kp.max_characteristic_radius_m)) + " m"
        : kp.max_radius_supports > 0       ? "<= " + fmt("%g", double(kp.max_radius_supports)) + " r"
                                           : std::string("uncapped"))
    << "; each claims " << (kp.claim_min_supports > 0 ? "max(rho1, " + fmt("%g", double(kp.claim_min_supports)) + " r)" : std::string("rho1"))
    << "; "
    << (kp.exclude_boundary ? "no keypoint " + (kp.boundary_band_supports > 0 ? "within " + fmt("%g", double(kp.boundary_band_supports)) +
                                                                                    " r of a boundary point"
                                                                              : std::string("on a boundary point")) +
                                  " (angular gap > " + fmt("%g", std::round(kp.boundary_gap_rad * 180 / 3.14159265358979)) +
                                  " deg among the neighbours within " + fmt("%g", double(kp.boundary_radius_supports)) + " r)"
                            : std::string("boundary kept"))
    << "; descriptors over "
    << (t.features.descriptor.characteristic_scale_supports > 0
            ? "rho1 clamped to [r, " + fmt("%g", double(t.features.descriptor.characteristic_scale_supports)) + " r]"
            : std::string("r"))
    << " | r as small as the density allows; rho1 = 2 / sqrt(lambda1) claims its sphere; boundary points and their "
       "neighbourhood excluded |\n";
  const char* kind = t.decision.kind == DecisionRule::kNearestCentre ? "nearest centre"
                     : t.decision.kind == DecisionRule::kCentres   ? "several centres per category"
                     : t.decision.kind == DecisionRule::kNearestReference
                         ? "nearest reference per category (every training vector; softmin scores)"
                         : "k-NN";
  o << "| decision | " << kind;
  if (t.decision.kind == DecisionRule::kNearestNeighbours) o << " (k = " << t.decision.neighbours << ")";
  if (t.decision.kind == DecisionRule::kCentres) o << " (" << t.decision.centres_per_category << " per category)";
  o << ", L1 " << (t.decision.pca_explained_variance > 0 ? "after PCA (" + pct(100 * t.decision.pca_explained_variance) +
                                                                 " % of the variance, BoG <= " + std::to_string(t.bog_pca_dims) + " dims)"
                                                           : "on the histograms (BoG reduced to " + std::to_string(t.bog_pca_dims) +
                                                                 " dims)")
    << " | one K-means centre per category, L1 |\n";
  o << "| exploration grid (category changes) | keypoint counts ";
  for (size_t i = 0; i < r.grid.size(); ++i) o << (i ? ", " : "") << r.grid[i];
  o << (p.explore_step > 1 ? " (coarser than the paper's every keypoint: changes between grid points are not seen)" : "")
    << " | every keypoint 1..55 |\n";
  o << "| threads | " << r.threads << " | |\n\n";
}

void write_accuracy(std::ostringstream& o, const EvalResult& r) {
  const std::vector<std::string> stages = main_stage_names(r);
  o << "## Accuracy per method and stage (%)\n\n";
  o << "Ours, pooled over folds, with the paper's figure (sec. 5) in brackets. The paper equates its 10 kp stage "
       "with ~10 % visible and 25 kp with ~20 %, so its 10 % / 20 % figures are shown under both.\n\n";
  o << "| method |";
  for (const std::string& s : stages) o << " " << s << " |";
  o << "\n|---|";
  for (size_t i = 0; i < stages.size(); ++i) o << "---:|";
  o << "\n";
  for (MethodId m : r.params.methods) {
    o << "| " << method_label(m) << " |";
    for (const std::string& s : stages) {
      const Tally t = accuracy(r.decisions, s, m);
      o << " **" << pct(t.percent(), 1) << "**";
      const double paper = paper_accuracy(m, s);
      if (!std::isnan(paper)) o << " (" << pct(paper) << ")";
      o << " |";
    }
    o << "\n";
  }
  o << "| *best* |";
  for (const std::string& s : stages) {
    double best = -1;
    MethodId bm = r.params.methods.front();
    for (MethodId m : r.params.methods)
      if (double a = accuracy(r.decisions, s, m).percent(); a > best) best = a, bm = m;
    double paper_best = kNaN;
    for (MethodId m : {MethodId::kVFH, MethodId::kKGH, MethodId::kBoK, MethodId::kBoG}) {
      const double pa = paper_accuracy(m, s);
      if (!std::isnan(pa) && (std::isnan(paper_best) || pa > paper_best)) paper_best = pa;
    }
    o << " " << pct(best, 1) << " " << method_label(bm);
    if (!std::isnan(paper_best)) o << " (" << pct(paper_best) << " BoK)";
    o << " |";
  }
  o << "\n| *mean visible %* |";
  for (const std::string& s : stages) {
    const StageStats* st = stats_of(r, s);
    o << " " << (st ? pct(st->mean_visible_percent, 1) : "–") << " |";
  }
  o << "\n| *mean keypoints* |";
  for (const std::string& s : stages) {
    const StageStats* st = stats_of(r, s);
    o << " " << (st ? pct(st->mean_keypoints, 1) : "–") << " |";
  }
  o << "\n\nBalanced accuracy (mean of the per-category recalls, each category weighing the same):\n\n| method |";
  for (const std::string& s : stages) o << " " << s << " |";
  o << "\n|---|";
  for (size_t i = 0; i < stages.size(); ++i) o << "---:|";
  o << "\n";
  for (MethodId m : r.params.methods) {
    o << "| " << method_label(m) << " |";
    for (const std::string& s : stages) o << " " << pct(balanced_accuracy(r.decisions, s, m, r.categories.size()), 1) << " |";
    o << "\n";
  }
  o << "\nChance is " << pct(100.0 / double(std::max<size_t>(1, r.categories.size())), 0) << " %.\n\n";
}

void write_confusions(std::ostringstream& o, const EvalResult& r) {
  const std::vector<std::string> stages = main_stage_names(r);
  for (const char* stage : {"full", "10kp", "25kp"}) {
    if (std::find(stages.begin(), stages.end(), stage) == stages.end()) continue;
    const char* table = std::string_view(stage) == "full" ? "Table 1" : std::string_view(stage) == "10kp" ? "Table 2" : "Table 3";
    o << "### Confusion, stage " << stage << " (paper " << table << ")\n\n";
    o << "Query rows (true category, one sub-row per method), result columns (%), and the paper's correct % for the "
         "same query and method.\n\n| query | method |";
    for (const std::string& c : r.categories) o << " " << c << " |";
    o << " paper |\n|---|---|";
    for (size_t i = 0; i < r.categories.size(); ++i) o << "---:|";
    o << "---:|\n";
    std::vector<std::vector<std::vector<double>>> conf;
    for (MethodId m : r.params.methods) conf.push_back(confusion_percent(r.decisions, stage, m, r.categories.size()));
    for (size_t q = 0; q < r.categories.size(); ++q) {
      for (size_t mi = 0; mi < r.params.methods.size(); ++mi) {
        const MethodId m = r.params.methods[mi];
        const char* label = paper_category_label(r.categories[q]);
        o << "| " << (mi == 0 ? (label ? label : r.categories[q].c_str()) : "") << " | " << method_label(m) << " |";
        for (size_t c = 0; c < r.categories.size(); ++c) {
          const std::string v = pct(conf[mi][q][c]);
          o << " " << (c == q ? "**" + v + "**" : v) << " |";
        }
        o << " " << pct(paper_diagonal(stage, r.categories[q], m)) << " |\n";
      }
    }
    o << "\n";
  }
}

void write_changes(std::ostringstream& o, const EvalResult& r) {
  static const std::map<size_t, std::pair<double, double>> kPaper = {{10, {0.41, 0.46}}, {25, {1.3, 1.6}}, {55, {2.8, 3.9}}};
  o << "## Category changes along the exploration (sec. 4)\n\n";
  o << "Method: **" << method_label(r.change_method) << "** (the recogniser's default, fixed before testing). For each test "
       "view, the decisions at keypoint counts ";
  for (size_t i = 0; i < r.grid.size(); ++i) o << (i ? ", " : "") << r.grid[i];
  o << "; a view is finally correct when its full-view decision is. A stage whose k exceeds the view's keypoints is the "
       "full view, so the sequence stops changing there.\n\n";
  o << "| up to | changes, finally correct | finally incorrect | views correct / incorrect | paper correct / incorrect |\n";
  o << "|---|---:|---:|---:|---:|\n";
  for (const ChangeRow& c : r.changes) {
    auto p = kPaper.find(c.up_to_keypoints);
    o << "| " << c.up_to_keypoints << " kp | " << fmt("%.2f", c.mean_correct) << " | " << fmt("%.2f", c.mean_incorrect)
      << " | " << c.views_correct << " / " << c.views_incorrect << " | "
      << (p != kPaper.end() ? fmt("%.2f", p->second.first) + " / " + fmt("%.2f", p->second.second) : "–") << " |\n";
  }
  o << "\nEvolution curves (decided category against visible % of the full cloud, one line per view, as the paper's "
       "Figures 5-6): [finally correct](evolution_correct.svg), [finally incorrect](evolution_incorrect.svg).\n\n";
}

void write_streams(std::ostringstream& o, const EvalResult& r) {
  if (r.streams.empty()) return;
  const SessionParams& sp = r.params.session;
  const size_t min_kp = uses_keypoints(r.change_method) ? sp.min_keypoints : 0;
  o << "## Streaming: when the decision settles (ScanSession)\n\n";
  o << "Every view streamed top to bottom through a ScanSession of its fold's model (method **"
    << method_label(r.change_method) << "**), in chunks of " << pct(100 * r.params.stream_chunk_fraction, 1)
    << " % of the full 3D cloud's points. A view counts at its first settled decision: precision = share of those "
       "that name the true category, visible % = how much of the full cloud had been seen then. Goal: precision >= 95 % "
       "with settlement before 30 % visible on average.\n\n";
  if (r.settle_margins.empty())
    o << "| settled when | views settled | precision | mean visible % | median visible % |\n|---|---:|---:|---:|---:|\n";
  auto row = [&](const std::string& label, const SettleRow& s) {
    o << "| " << label << " | " << s.settled_views << " / " << s.views << " (" << pct(s.settled_percent(), 1) << " %) | "
      << pct(s.precision_percent(), 1) << " % | " << pct(s.mean_visible_percent, 1) << " | "
      << pct(s.median_visible_percent, 1) << " |\n";
  };
  if (!r.settle_margins.empty()) {
    o << "Each model calibrated where its decisions settle on held-out folds of its own training objects ("
      << r.params.train.calibration_folds << " inner folds by object; nothing of the test views): the smallest margin "
         "between the best two scores at which held-out decisions were " << pct(100 * r.params.train.settle_precision)
      << " % right. Settle margin per model:";
    for (size_t i = 0; i < r.settle_margins.size(); ++i)
      o << (i ? "," : "") << " " << fmt("%.3f", r.settle_margins[i]) << " (held out "
        << pct(100 * r.calibration_accuracy[i], 1) << " % right)";
    o << ". The sweep below recomputes settling at fixed confidences from the recorded ones (without the session's "
         "hold rule), for comparison only.\n\n";
    o << "| settled when | views settled | precision | mean visible % | median visible % |\n|---|---:|---:|---:|---:|\n";
  }
  const SettleRow session = settle_summary(r.streams, -1);
  row("**session default** (calibrated margin, confidence >= " + fmt("%.2f", sp.settle_confidence) + ", the winner held " +
          std::to_string(sp.stability_window) + " chunks, the newest included" +
          (session.unknown ? "; " + std::to_string(session.unknown) + " settled as unknown, counted wrong" : std::string()) + ")",
      session);
  for (double t : r.params.settle_sweep) row("confidence >= " + fmt("%.2f", t), settle_summary(r.streams, t, min_kp));
  o << "\nPer category, the session's own flag:\n\n| category | views settled | precision | mean visible % |\n"
       "|---|---:|---:|---:|\n";
  for (size_t c = 0; c < r.categories.size(); ++c) {
    const SettleRow s = settle_summary(r.streams, -1, 0, static_cast<int>(c));
    o << "| " << r.categories[c] << " | " << s.settled_views << " / " << s.views << " | " << pct(s.precision_percent(), 1)
      << " % | " << pct(s.mean_visible_percent, 1) << " |\n";
  }
  size_t final_correct = 0, decided = 0;
  for (const StreamTrace& t : r.streams)
    if (!t.winners.empty()) ++decided, final_correct += t.winners.back() == t.truth;
  o << "\nLast decision of each stream (the whole view seen): " << final_correct << " / " << decided << " correct ("
    << pct(decided ? 100.0 * double(final_correct) / double(decided) : 0, 1) << " %). Every chunk is in "
    << "[streams.csv](streams.csv).\n\n";
}

}  // namespace

double paper_accuracy(MethodId method, std::string_view stage) {
  const int col = paper_method_column(method);
  if (col < 0) return kNaN;
  static constexpr double kFull[] = {64, 89, 89, 83}, k10[] = {57, 32, 64, 54}, k20[] = {60, 44, 68, 66};
  if (stage == "full") return kFull[col];
  if (stage == "10%" || stage == "10kp") return k10[col];
  if (stage == "20%" || stage == "25kp") return k20[col];
  return kNaN;
}

std::string markdown_report(const EvalResult& r) {
  std::ostringstream o;
  o << "# Glimpse evaluation: the paper's protocol (Rozsa & Sziranyi, sec. 3.4, 4, 5)\n\n";
  write_protocol(o, r);
  write_accuracy(o, r);
  o << eval_internal::size_section(r);
  o << eval_internal::robustness_section(r);
  o << eval_internal::keypoints_section(r);
  o << eval_internal::keypoint_ablation_section(r);
  o << "## Confusion tables\n\n";
  write_confusions(o, r);
  write_changes(o, r);
  write_streams(o, r);
  o << open_set_section(r);
  o << "## Things that look wrong\n\n";
  if (r.notes.empty()) o << "Nothing flagged.\n";
  for (const std::string& n : r.notes) o << "- " << n << "\n";
  o << "\n## Timings\n\n| phase | seconds | detail |\n|---|---:|---|\n";
  for (const PhaseTiming& t : r.timings) o << "| " << t.phase << " | " << fmt("%.1f", t.seconds) << " | " << t.detail << " |\n";
  o << "| **total** | **" << fmt("%.1f", r.total_seconds) << "** | " << r.threads
    << " threads; wall-clock time, on a machine possibly shared with other jobs |\n\n";
  o << "Every decision is in [decisions.csv](decisions.csv).\n";
  return o.str();
}


}  // namespace glimpse
