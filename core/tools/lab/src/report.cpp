// The evaluation report a person reads: the markdown sections in the order they appear (the CSV, SVG and
// terminal writers and the report folder are evaluation_writers.cpp's; the exploration's category changes
// and the streams' settling are evaluation_report_streams.cpp's).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "glimpse/lab/evaluation.h"
#include "report_format.h"
#include "protocol.h"
#include "glimpse/learning/model_internals.h"

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
  // Across sources the count is of both sides; the cross-source row below splits it.
  o << "| data | " << r.source << " (" << r.object_ids.size() << (r.cross_source ? " objects learnt and tested in all: " : " objects: ")
    << cats << ") | SHREC 2007, same 5 categories, 20 objects each |\n";
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
      << "), tested on every view of **" << test << "** (" << count(true) << "); "
      << (tests_learnt_objects(r) ? "**the tested objects were learnt too** (a source on both sides: resubstitution, not a held-out figure)"
                        : "nothing of the test collections is learnt or calibrated on")
      << " | – |\n";
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
  // glimpse-lab compare reads this row: runs of different seeds are not the same views (nor, for the zoo,
  // the same objects).
  o << "| seed (`--seed`) | " << p.seed << " | – |\n";
  o << "| keypoint stage cut | keypoints of the full view sorted by height; prefix = points above the k-th highest minus "
    << p.cut_margin_supports << " support radii; features re-extracted on that prefix | prefix with k visible keypoints |\n";
  o << "| fraction stages | top prefix holding the fraction of the FULL 3D cloud's point count | ~10 %, ~20 % visible |\n";
  if (!r.cross_source)
    o << "| cross-validation | " << p.folds << "-fold by object, stratified by category, seed " << p.seed
      << "; accuracy pooled over folds | not stated; 57 of the 60 per-category figures of Tables 1-3 are k/18: 18 "
         "test views (3 objects x 6 views) per category, held out or not is not said |\n";
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
  for (float e : p.train_elevations_deg)
    trained_on += "; plus the same azimuths from " + pct(e) + " deg elevation (training only)";
  for (const ScanCondition& c : p.train_conditions)
    trained_on += "; plus the same azimuths seen by a " + describe(c) +
                  " (`--train-sensors`, training only), through the scan filters down to the model's density (the "
                  "median of its ideal training views)";
  {
    std::map<std::string, size_t> extra;
    if (!r.cross_source)
      for (size_t i = 0; i < r.object_fold.size(); ++i)
        if (r.object_fold[i] < 0) ++extra[r.object_source[i]];
    for (const auto& [source, n] : extra)
      trained_on += "; plus every object of " + source + " (" + std::to_string(n) + ", training only, never tested)";
  }
  o << "| training clouds (`--train-on`, `--train-prefixes`, `--train-elevations`, `--train-sensors`) | " << trained_on
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
  if (needs(p.methods, MethodId::kFusion) && t.fusion_head.c > 0) {
    o << "| fusion's logistic decision | (1 - w) x the mean of the components' scores + w x a one-vs-rest logistic "
         "regression (LIBLINEAR, C " << fmt("%g", t.fusion_head.c) << ") over each histogram's additive chi2 map ("
      << t.fusion_head.sample_steps << " steps, interval " << fmt("%g", t.fusion_head.sample_interval)
      << "); w of ";
    for (size_t i = 0; i < t.fusion_head_shares.size(); ++i) o << (i ? ", " : "") << fmt("%g", t.fusion_head_shares[i]);
    o << ", the one most often right on held-out folds of the model's own training objects (" << t.calibration_folds
      << " inner folds); w per model:";
    for (size_t i = 0; i < r.fusion_head_shares.size(); ++i) o << (i ? "," : "") << " " << fmt("%g", r.fusion_head_shares[i]);
    o << " | – |\n";
  }
  o << "| exploration grid (category changes) | keypoint counts ";
  for (size_t i = 0; i < r.grid.size(); ++i) o << (i ? ", " : "") << r.grid[i];
  o << (p.explore_step > 1 ? " (coarser than the paper's every keypoint: changes between grid points are not seen)" : "")
    << " | every keypoint 1..55 |\n";
  o << "| threads | " << r.threads << " | |\n\n";
}

// A table with a cell per method (rows, the run's order) and stage (columns).
void method_stage_table(std::ostringstream& o, const EvalResult& r, const std::vector<std::string>& stages,
                        const std::function<std::string(MethodId, const std::string&)>& cell) {
  o << "| method |";
  for (const std::string& s : stages) o << " " << s << " |";
  o << "\n|---|";
  for (size_t i = 0; i < stages.size(); ++i) o << "---:|";
  o << "\n";
  for (MethodId m : r.params.methods) {
    o << "| " << method_label(m) << " |";
    for (const std::string& s : stages) o << " " << cell(m, s) << " |";
    o << "\n";
  }
}

void write_accuracy(std::ostringstream& o, const EvalResult& r) {
  const std::vector<std::string> stages = main_stage_names(r);
  o << "## Accuracy per method and stage (%)\n\n";
  o << "Ours, pooled over folds, with the paper's figure (sec. 5) in brackets. The paper equates its 10 kp stage "
       "with ~10 % visible and 25 kp with ~20 %, so its 10 % / 20 % figures are shown under both.\n\n";
  method_stage_table(o, r, stages, [&](MethodId m, const std::string& s) {
    const double paper = paper_accuracy(m, s);
    return "**" + pct(accuracy(r.decisions, s, m).percent(), 1) + "**" + (std::isnan(paper) ? "" : " (" + pct(paper) + ")");
  });
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
  o << "\n\nBalanced accuracy (mean of the per-category recalls, each category weighing the same):\n\n";
  method_stage_table(o, r, stages, [&](MethodId m, const std::string& s) {
    return pct(balanced_accuracy(r.decisions, s, m, r.categories.size()), 1);
  });
  std::set<int> tested;
  for (const StageDecision& d : r.decisions)
    if (d.truth >= 0) tested.insert(d.object);
  constexpr double kLevel = 0.95;
  constexpr size_t kDraws = 2000;
  o << "\nHow far each accuracy could move with another draw of test objects: the interval holding "
    << pct(100 * kLevel) << " % of the accuracies of " << kDraws << " resamples of the " << tested.size()
    << " tested objects, with replacement (an object, not a view, is the unit: one object's views are mostly right or "
       "wrong together):\n\n";
  method_stage_table(o, r, stages, [&](MethodId m, const std::string& s) {
    const AccuracyInterval ci = accuracy_interval(r.decisions, s, m, kLevel, kDraws);
    return pct(ci.low, 1) + "-" + pct(ci.high, 1);
  });
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
  o << eval_internal::changes_section(r);
  o << eval_internal::streams_section(r);
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
