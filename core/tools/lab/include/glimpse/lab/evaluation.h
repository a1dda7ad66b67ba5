// The paper's evaluation protocol (sec. 3.4, 4, 5): single HPR views of whole objects, a progressive
// top-to-bottom exploration of each view, stratified cross-validation by object, accuracy and
// confusion per method per stage, category changes along the exploration, and a report a person can
// read (markdown tables, a CSV of every decision, SVG evolution curves like Figures 5-6).
//
// The pure pieces (folds, stage cuts, metrics, change counting, writers) are free functions over
// plain data so tests can call them with hand-made inputs; run_evaluation strings them together.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/geometry/scan_filters.h"
#include "glimpse/lab/metrics.h"
#include "glimpse/learning/metrics.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/object_views.h"
#include "glimpse/learning/train_params.h"
#include "glimpse/session/session.h"
#include "glimpse/views/dataset.h"
#include "glimpse/views/exploration.h"
#include "glimpse/views/scan_conditions.h"
#include "glimpse/views/sensors.h"

namespace glimpse {

// ---- Objects ---------------------------------------------------------------------------------------

// How the protocol uses an object: cross-validation (all objects), or the two sides of a cross-source
// evaluation (train on every object of some collections, test on every object of others).
enum class EvalRole : uint8_t {
  kCrossValidate,  // in the folds: learnt by the other folds' models, tested by its own fold's
  kTrainOnly,      // learnt by every model, never tested
  kTestOnly,       // tested by the one model of all kTrainOnly objects, never learnt
  kUnknown,        // of a category no model learns: tested (by one fold's model in a cross-validation),
                   // it should come out "unknown" (the open-set section)
};

struct EvalObject {
  std::string category;
  std::string id;
  Mesh mesh;              // upright (+z), real-life size, on the ground
  std::string source;     // the collection: the dataset folder's name ("shrec07"), "zoo"
  bool any_pose = false;  // no natural up (CategorySize::any_pose): each view in a random pose of its own
  EvalRole role = EvalRole::kCrossValidate;
};

// Every object of a dataset folder (scan_dataset + load_object with `seed` and `sizing`), at most
// `max_per_category` per category (0 = all; the first ones in manifest order). Loaded in parallel.
Expected<std::vector<EvalObject>> load_dataset_objects(const std::string& dir, uint64_t seed,
                                                       size_t max_per_category = 0, int threads = 0,
                                                       const Sizing& sizing = {});
// make_zoo(per_category, seed): the procedural stand-in for the dataset.
std::vector<EvalObject> zoo_objects(size_t per_category, uint64_t seed);

// The size-blind ablation: every object scaled to `height_m` (upright height), on the ground.
std::vector<EvalObject> common_height(std::vector<EvalObject> objects, float height_m);

// The categories of `objects` in the paper's order (human, chair, table, mechanic, fourleg) when
// they are among them, then any others sorted by name.
std::vector<std::string> paper_category_order(const std::vector<EvalObject>& objects);

// The robustness matrices: `small` (the default run's: density 0.25x and 4x, tilt 5 deg, depth camera
// at 2 m with and without floor and outliers, LiDAR at 10 m) and `full` (depth camera at 1-3 m x 0-45
// deg, LiDAR at 5-15 m, density 0.25x-4x, tilt 2-10 deg, floor, outliers). Each starts with the ideal
// views through the same filters, the row every other one is compared with.
// "none", "small", "full" or "sensors" (the depth camera from -10 to 60 degrees at 0.8-4 m, LiDAR of
// 16, 32 and 64 beams at 5-20 m).
std::vector<ScanCondition> robustness_conditions(std::string_view matrix);

// ---- Cross-validation -------------------------------------------------------------------------------

// stratified_folds (model.h) deals the objects to the folds.

// ---- The protocol ------------------------------------------------------------------------------------

struct EvalParams {
  size_t points_per_object = 6000;  // 0: mesh vertices as points (the paper); else area-weighted samples
  size_t views_per_object = 6;      // the first n of paper_viewpoints (azimuth 0, 60, ..., 300 deg)
  // Training-only views besides the tested ones: the same azimuths from these elevations (deg above the
  // horizon; the tested views stay at the paper's 30), so a model learns cameras mounted low or high.
  std::vector<float> train_elevations_deg;
  // Training-only views taken by simulated sensors (condition_view at each of these conditions, the
  // same azimuths, through the scan filters at the density the ideal training views have), so a model
  // learns what a real camera returns as well as the paper's ideal views. Learnt objects only.
  std::vector<ScanCondition> train_conditions;
  double hpr_radius_factor = 100;
  std::vector<Stage> stages = paper_stages();
  float cut_margin_supports = 1.5f;  // keypoint cut margin in support radii (see keypoint_prefix)
  int folds = 5;  // cross-validation; a cross-source evaluation (kTrainOnly/kTestOnly objects) trains one model
  // Few-shot: every model learns at most this many objects of each category (of those it could learn,
  // every source together), drawn by the seed and the fold; what it tests is unchanged. 0: all.
  size_t objects_per_category = 0;
  std::vector<MethodId> methods = {std::begin(kAllMethods), std::end(kAllMethods)};
  size_t explore_max_keypoints = 55;
  size_t explore_step = 5;
  std::vector<size_t> change_up_to = {10, 25, 55};
  // Every test view is also streamed top to bottom through a ScanSession of its fold's model, in
  // chunks of this fraction of the full 3D cloud's points, with the best method (0: no streaming).
  double stream_chunk_fraction = 0.02;
  SessionParams session;
  std::vector<double> settle_sweep = {0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9};
  // The test views of the main tables (training views are always the ideal ones); a non-ideal
  // condition's views go through `filters` before anything is measured.
  ScanCondition test_condition;
  ScanFilterParams filters;
  // The robustness matrix: the default method at the main stages under each condition, on the first
  // matrix_views_per_object of each tested object's views, with every fold's model.
  std::vector<ScanCondition> matrix;  // glimpse-lab eval runs robustness_conditions("small") by default
  size_t matrix_views_per_object = 2;
  int threads = 0;  // 0 = all cores; results do not depend on it
  uint64_t seed = 42;
  // false: no training cloud is marked augmented, so no model learns apart the clouds novelty measures
  // against (a second training, of the unmarked clouds alone; for ablations that read only the winners).
  bool novelty_models = true;
  // Non-empty: every fold's model writes the histograms it computes, of its training clouds and of
  // every tested stage, to DIR/fold<k>.csv (other classifiers can then be tried on exactly what the
  // decision stages see). The folder must exist.
  std::string export_histograms_dir;
  // threads and seed are taken from the fields above; train.partial_prefixes (fractions of each
  // training VIEW's points) are the top-down prefixes trained on besides the views.
  TrainParams train;
};

struct PhaseTiming {
  std::string phase;
  double seconds = 0;
  std::string detail;
};

// Mean over views, per category and stage.
struct StageStats {
  std::string stage;
  std::vector<double> keypoints;        // per category
  std::vector<double> visible_percent;  // per category
  std::vector<size_t> failed;           // per category: clouds whose features failed
  double mean_keypoints = 0, mean_visible_percent = 0;
  double feature_seconds = 0;           // CPU time spent extracting this stage's clouds (distinct prefixes)
  // Keypoint stages only, over the views whose full view has at least k keypoints (the cut is real):
  // how many keypoints re-extraction finds on the prefix, which checks the cut's approximation.
  size_t cut_views = 0;
  double cut_mean_keypoints = 0, cut_visible_percent = 0;
  size_t cut_min_keypoints = 0, cut_max_keypoints = 0;
};

// One condition of the robustness matrix: the default method's accuracy at the main stages.
struct RobustnessRow {
  ScanCondition condition;
  std::vector<double> accuracy;  // per main stage, %: the closest category right
  std::vector<double> accepted;  // per main stage, %: right and not called unknown
  std::vector<double> balanced;  // per main stage, %
  double unknown_accepted = NAN;  // % of the views of objects of no learnt category accepted (full view); NaN: none tested
  // Each known view's full-view outcome beside its points after the filters (accuracy against points).
  struct ViewOutcome {
    size_t points = 0;
    bool right = false, accepted = false;
  };
  std::vector<ViewOutcome> full_views;
  size_t views = 0, failed = 0;  // failed: no decision on the full view (too few points, ...)
  double median_points_raw = 0;  // as the sensor returned them
  double median_points = 0;      // after the filters
  size_t ground_views = 0;       // views in which a ground plane was removed
  double seconds = 0;
};

// Another evaluation's accuracy shown beside this one's (the size-blind ablation, the keypoint ablation).
struct AblationRow {
  std::string group = "size";    // the report section: "size" (how much is size), "keypoints"
  std::string label;             // what was changed
  MethodId method = MethodId::kFusion;
  std::vector<double> accuracy;  // per main stage, %
  std::vector<double> balanced;  // per main stage, %
};

struct EvalResult {
  EvalParams params;
  std::string source;  // "meshes in DIR" / "procedural zoo, N per category"
  bool cross_source = false;                // kTrainOnly/kTestOnly objects: one model, no folds
  std::vector<std::string> train_sources;   // collections learnt from
  std::vector<std::string> test_sources;    // collections tested
  std::vector<std::string> any_pose_categories;  // their objects' views are taken in random poses
  std::vector<std::string> unknown_categories;   // of the kUnknown objects (never learnt)
  std::vector<int> object_unknown_class;         // per object: index into unknown_categories, -1 known
  std::vector<double> novelty_thresholds;        // per model: its calibrated operating point
  size_t novelty_models = 0;                     // models whose novelty is their novelty model's (ModelImpl::novelty)
  std::vector<std::string> categories;
  std::vector<std::string> object_ids;      // "category/id" per object
  std::vector<int> object_truth;
  std::vector<int> object_fold;             // -1: training only (cross-source)
  std::vector<std::string> object_source;
  std::vector<size_t> object_points;        // full 3D cloud size
  std::vector<StageDecision> decisions;
  std::vector<StageStats> stage_stats;      // main stages then the exploration grid
  std::vector<size_t> grid;
  MethodId change_method = MethodId::kFusion;   // the default method (train.default_method when evaluated)
  std::vector<ChangeRow> changes;
  std::vector<ExplorationTrace> traces;     // of change_method
  std::vector<StreamTrace> streams;         // of change_method, every tested view
  std::vector<double> settle_margins;       // per model: calibrated on held-out folds of its training set
  std::vector<double> calibration_accuracy; // per model: its held-out decisions' share right
  std::vector<double> fusion_head_shares;   // per model: the logistic decision's share in the fusion (Calibration)
  std::vector<double> probability_temperatures;  // per model: its probabilities' temperature (0: none)
  std::vector<double> settle_probabilities;      // per model: where its streams settle (0: on the margin)
  std::vector<PhaseTiming> timings;
  double total_seconds = 0;
  int threads = 1;
  std::vector<std::string> notes;           // anything that looks wrong
  std::vector<AblationRow> ablations;       // filled by the caller (add_ablation)
  std::vector<RobustnessRow> robustness;    // the robustness matrix, in params.matrix's order
  std::vector<double> trained_density;      // per model: median relative density of its training views
};

// What a run's views held: "full views 46.7 kp, 84.3 % >= 25" (mean keypoints of the full views and the
// share of tested views with at least 25, when the 25 kp stage was run).
std::string keypoint_summary(const EvalResult& r);

// The accuracy of each of `other`'s methods at `result`'s main stages, as ablation rows labelled `label`.
void add_ablation(EvalResult& result, const EvalResult& other, const std::string& label,
                  const std::string& group = "size");

struct EvalProgress {
  std::string phase;
  size_t done = 0, total = 0;
};
using EvalProgressFn = std::function<void(const EvalProgress&)>;

Expected<EvalResult> run_evaluation(const std::vector<EvalObject>& objects, const EvalParams& params,
                                    std::string source, const EvalProgressFn& progress = {});

// ---- Report ------------------------------------------------------------------------------------------

// The paper's figures: accuracy (%) by method and stage ("full", "10%", "20%"; the paper equates
// 10 kp with ~10 % and 25 kp with ~20 %), NaN where the paper gives none.
double paper_accuracy(MethodId method, std::string_view stage);

std::string markdown_report(const EvalResult& result);
std::string decisions_csv(const EvalResult& result);
// One row per streamed chunk: fold, object, view, truth, chunk, visible fraction, winner, confidence, settled.
std::string streams_csv(const EvalResult& result);
// Figures 5-6: decided category against visible % of the full cloud, one polyline per view, one
// panel per true category; `correct` picks the finally-correct or finally-incorrect views.
std::string evolution_svg(const std::vector<ExplorationTrace>& traces, const std::vector<std::string>& categories,
                          bool correct, std::string_view title);
// The report's open-set section (empty without objects of an unknown category).
std::string open_set_section(const EvalResult& result);
// The report's section on the calibrated probabilities of the default method: per main stage, expected
// calibration error, log loss and Brier score of the raw scores and of the probabilities (empty when
// no decision has probabilities), and its reliability diagram (one panel per main stage).
std::string probabilities_section(const EvalResult& result);
std::string reliability_svg(const EvalResult& result);
// A short plain-text accuracy table (method x main stage) for a terminal.
std::string summary_table(const EvalResult& result);
// A cross-source run whose test sources include a training one (--train X --test X): the tested objects
// were learnt too, so its figures are resubstitution, not held out.
bool tests_learnt_objects(const EvalResult& result);

// ---- Leave one source out: each source tested by a model of the others --------------------------------

// `runs`: one cross-source run per source left out, tested on it. Per left-out source, stage and category
// of `method`: "closest" (the winner right, "unknown" ignored) beside "right and accepted" (right and not
// called unknown), each with the interval holding 95 % of object-bootstrap resamples, and the known views
// called unknown.
struct SourceRow {
  std::string left_out;                   // the tested source's name (EvalResult::test_sources)
  std::string stage, category;            // category empty: every category of the source
  size_t views = 0, objects = 0;
  Tally closest, accepted_right;
  AccuracyInterval closest_interval, accepted_interval;
  size_t rejected = 0;  // known views called unknown
};
std::vector<SourceRow> leave_one_source_out_rows(const std::vector<EvalResult>& runs, MethodId method);
// leave-one-out.md: the table of every source, then per category.
std::string leave_one_source_out_report(const std::vector<EvalResult>& runs, MethodId method);

// report.md, decisions.csv, evolution_correct.svg, evolution_incorrect.svg, streams.csv in `dir` (created).
Status write_report(const EvalResult& result, const std::string& dir);

}  // namespace glimpse
