// The report's protocol table: every setting of the run beside the paper's (sec. 3.4, 4), row by row in
// the order they appear: data, views and stages, training clouds, methods and codebooks, keypoints,
// decision, the exploration grid.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "glimpse/lab/evaluation.h"
#include "glimpse/learning/model_internals.h"
#include "protocol.h"
#include "report_format.h"

namespace glimpse::eval_internal {

namespace {

std::string join_methods(const std::vector<MethodId>& ms) {
  std::string s;
  for (MethodId m : ms) s += (s.empty() ? "" : ", ") + std::string(method_name(m));
  return s;
}

// Where the objects come from and how many of each category; across sources, what each side holds.
void data_rows(std::ostringstream& o, const EvalResult& r) {
  std::map<std::string, size_t> per_cat;
  for (int t : r.object_truth)
    if (t >= 0) ++per_cat[r.categories[static_cast<size_t>(t)]];
  std::string cats;
  for (const std::string& c : r.categories) cats += (cats.empty() ? "" : ", ") + c + " " + std::to_string(per_cat[c]);
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
}

// The object clouds, the viewpoints, the stages and their cuts, the seed and the folds.
void view_rows(std::ostringstream& o, const EvalResult& r) {
  const EvalParams& p = r.params;
  size_t min_pts = std::numeric_limits<size_t>::max(), max_pts = 0;
  double mean_pts = 0;
  for (size_t n : r.object_points) min_pts = std::min(min_pts, n), max_pts = std::max(max_pts, n), mean_pts += double(n);
  if (!r.object_points.empty()) mean_pts /= double(r.object_points.size());
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
}

// What each model learns from: full views, their prefixes, tilts, other elevations and sensors, other sources.
void training_clouds_row(std::ostringstream& o, const EvalResult& r) {
  const EvalParams& p = r.params;
  const std::vector<double>& prefixes = p.train.partial_prefixes;
  std::string trained_on = "full views only";
  if (!prefixes.empty()) {
    trained_on = "full views + top-down prefixes holding ";
    for (size_t i = 0; i < prefixes.size(); ++i) trained_on += (i ? ", " : "") + pct(100 * prefixes[i]) + " %";
    trained_on += p.train.augmented_prefixes ? " of each training view" : " of each training view not augmented (augmented views whole only)";
  }
  if (p.train.tilt_deg > 0)
    trained_on += "; each training view (and its prefixes) turned by a random tilt of up to " + pct(p.train.tilt_deg) +
                  " deg (seeded), test views as seen";
  for (float e : p.train_elevations_deg)
    trained_on += "; plus the same azimuths from " + pct(e) + " deg elevation (training only)";
  if (!p.train_conditions.empty())
    trained_on += "; plus the same azimuths seen by a " + describe(p.train_conditions) +
                  " (`--train-sensors`, training only), through the scan filters down to the model's density (the "
                  "median of its ideal training views)";
  if (p.objects_per_category > 0)
    trained_on += "; **few-shot**: each model learns at most " + std::to_string(p.objects_per_category) +
                  " objects of each category (`--objects-per-category`, drawn by the seed and the fold), and tests "
                  "as with all of them";
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
}

// The methods and their codebooks (sec. 3.2.5-3.2.6).
void method_rows(std::ostringstream& o, const EvalParams& p) {
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
}

// Keypoints and descriptors (sec. 2.2, 3.2.1-3.2.2).
void keypoints_row(std::ostringstream& o, const TrainParams& t) {
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
}

// The decision (sec. 3.3) and the fusion's logistic decision with its share per model.
void decision_rows(std::ostringstream& o, const EvalResult& r) {
  const EvalParams& p = r.params;
  const TrainParams& t = p.train;
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
      << t.fusion_head.sample_steps << " steps, interval " << fmt("%g", t.fusion_head.sample_interval) << "), learning "
      << (t.fusion_head_rows_per_category > 0 ? "at most " + std::to_string(t.fusion_head_rows_per_category) +
                                                    " rows of each category (seeded)"
                                              : std::string("every row"))
      << "; w of ";
    for (size_t i = 0; i < t.fusion_head_shares.size(); ++i) o << (i ? ", " : "") << fmt("%g", t.fusion_head_shares[i]);
    o << ", the one most often right on held-out folds of the model's own training objects (" << t.calibration_folds
      << " inner folds); w per model:";
    for (size_t i = 0; i < r.fusion_head_shares.size(); ++i) o << (i ? "," : "") << " " << fmt("%g", r.fusion_head_shares[i]);
    o << " | – |\n";
  }
}

}  // namespace

std::string protocol_section(const EvalResult& r) {
  const EvalParams& p = r.params;
  std::ostringstream o;
  o << "## Protocol\n\n| parameter | ours | paper |\n|---|---|---|\n";
  data_rows(o, r);
  view_rows(o, r);
  training_clouds_row(o, r);
  method_rows(o, p);
  keypoints_row(o, p.train);
  decision_rows(o, r);
  o << "| exploration grid (category changes) | keypoint counts ";
  for (size_t i = 0; i < r.grid.size(); ++i) o << (i ? ", " : "") << r.grid[i];
  o << (p.explore_step > 1 ? " (coarser than the paper's every keypoint: changes between grid points are not seen)" : "")
    << " | every keypoint 1..55 |\n";
  o << "| threads | " << r.threads << " | |\n\n";
  return o.str();
}

}  // namespace glimpse::eval_internal
