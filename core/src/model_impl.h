// Private: what a trained Model holds beyond its public summary, and the per-cloud feature pipeline
// shared by train, classify and ScanSession.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <limits>
#include <memory>
#include <optional>

#include "glimpse/chi2_logistic.h"
#include "glimpse/classifiers.h"
#include "glimpse/decision.h"
#include "glimpse/features.h"
#include "glimpse/model.h"
#include "glimpse/train_params.h"

namespace glimpse {


struct ModelImpl {
  TrainParams params;
  Calibration calibration;
  KeypointCodebook bok;        // sec. 3.2.5, one codebook per method (the paper's cluster counts differ)
  KeypointCodebook bog;
  KeypointCodebook kgh;
  GraphVocabulary graphs;
  float kgh_max_distance_m = 1;
  std::array<std::optional<DecisionStage>, kMethodCount> stages;  // indexed by MethodId; never kFusion
  // The fusion's logistic decision over its components' histograms (fusion_head_methods), its share of
  // the fusion's scores in calibration.fusion_head_share. None: a model of format 6 or older, or trained
  // without one.
  std::optional<Chi2Logistic> fusion_head;
  // What novelty ("none of these") measures a cloud against when some training clouds were augmented
  // (TrainingCloud::augmented): the same training on the other clouds alone (its stages, its calibrated
  // novelty and threshold; the same categories, nothing nested further). A decision stage fitted with the
  // augmented clouds spans them too, and what it calls near grows with it (README, "Open set"). None:
  // nothing augmented (novelty from this model's own stages), or a model of format 7 or older.
  std::shared_ptr<const ModelImpl> novelty;
};

// The calibration novelty and its threshold come from: the novelty model's, else the model's own.
inline const Calibration& novelty_calibration(const ModelImpl& impl) {
  return impl.novelty ? impl.novelty->calibration : impl.calibration;
}

inline bool uses_keypoints(MethodId m) { return m == MethodId::kBoK || m == MethodId::kBoG || m == MethodId::kKGH; }
inline bool needs(const std::vector<MethodId>& methods, MethodId m) {  // `methods` lists m
  return std::find(methods.begin(), methods.end(), m) != methods.end();
}

// What the methods of a model need from one cloud.
struct CloudFeatures {
  std::vector<Vec3> positions;           // keypoint positions
  std::vector<Descriptor> descriptors;   // their 12-D descriptors
  std::optional<Eigen::VectorXf> vfh;
  std::optional<Eigen::VectorXf> esf;
  std::optional<Eigen::VectorXf> ush;
  std::optional<Eigen::VectorXf> size;  // visible_size: the size-only baseline
  size_t points = 0;
  float extent_m = 0;  // the largest bounding-box extent of the cleaned cloud
  // The same methods' features of the cloud's top-down prefix whose novelty joins the cloud's
  // (TrainParams::novelty_prefix); none when off or the prefix is too small.
  std::shared_ptr<const CloudFeatures> top_prefix;
};

// The base methods (every one but fusion) whose features and stages params.methods need: the
// methods themselves and, with fusion, its components.
std::vector<MethodId> base_methods(const TrainParams& params);

// The methods a model needs computed for `method` (fusion expands to its components).
std::vector<MethodId> component_methods(const ModelImpl& impl, MethodId method);

// What the given methods need of a feature state: keypoint positions and descriptors, and the
// whole-cloud descriptors (USH and size from the points and surfaces, VFH over the surfaces' normals,
// ESF); with params.novelty_prefix, the same of its top-down prefix (top_prefix). Shared by whole
// clouds (cloud_features) and streams (ScanSession).
Expected<CloudFeatures> method_features(const FeatureState& state, const TrainParams& params,
                                        const std::vector<MethodId>& methods, int threads);

// The model's parameters as `method`'s features are computed with: no top-down prefix where no
// calibrated novelty of `method` reads it.
TrainParams method_feature_params(const ModelImpl& impl, MethodId method);

// extract() + method_features; keypoints only when one of the methods needs them.
Expected<CloudFeatures> cloud_features(const Cloud& cloud, const TrainParams& params,
                                       const std::vector<MethodId>& methods, int threads,
                                       const CancelFn& cancel = {});

// classify_fused of one view (or of a model that does not filter): the model's filters on the whole
// cloud, then classify_filtered.
Expected<Classification> classify_scan(const Model& model, const Cloud& cloud,
                                       const std::vector<std::optional<Vec3>>& point_sensors, MethodId method,
                                       const CancelFn& cancel = {});

// The views of a scan from several sensor positions (classify_views.cpp): its points (indices) grouped
// by the direction their sensor looks from, seen from the scan's centroid; a sensor within
// kSameViewDeg of a view's first sensor is that view's, points without a sensor are one view. One
// view: a scan from one side.
inline constexpr float kSameViewDeg = 30.f;  // half the 60 deg between the paper's neighbouring viewpoints
std::vector<std::vector<uint32_t>> scan_views(const Cloud& cloud, const std::vector<std::optional<Vec3>>& point_sensors);

// Every model learns single views, and a cloud of an object's every side is unlike any of them, so
// classify_fused decides a scan of several views view by view (classify_scan of each) and joins the
// answers: the mean of their scores and of their per-category novelties, the winner the mean's
// argmax, the size judged on the largest view. Views a method cannot judge count only when none can.
// An error when no view can be decided alone (the caller then decides the fused scan).
Expected<Classification> classify_views(const Model& model, const Cloud& cloud,
                                        const std::vector<std::optional<Vec3>>& point_sensors,
                                        const std::vector<std::vector<uint32_t>>& views, MethodId method,
                                        const CancelFn& cancel = {});

// classify_fused's decision once the model's filters ran: `filtered` is filter_scan(cloud) with `report`
// (nullptr: the model does not filter), each kept point facing the sensor of its nearest raw point.
// The session calls it with the filter it ran to see whether anything would be filtered.
Expected<Classification> classify_filtered(const Model& model, const Cloud& cloud,
                                           const std::vector<std::optional<Vec3>>& point_sensors,
                                           const Cloud* filtered, const ScanFilterReport& report, MethodId method,
                                           std::chrono::steady_clock::time_point started, const CancelFn& cancel = {});

// The global histogram of one base method (every method but fusion).
Eigen::VectorXd method_histogram(const ModelImpl& impl, MethodId method, const CloudFeatures& f);

// A training cloud as it is learnt: turned by a random tilt of up to params.tilt_deg (seeded by
// params.seed and `salt`); its top-down prefixes are cut from this turned cloud.
Cloud training_view(const Cloud& cloud, const TrainParams& params, uint64_t salt);

// A training cloud whose features are already computed (train() computes them; the evaluation
// computes each view's features once and trains every fold from them).
struct TrainingSample {
  std::string category;
  std::string object_id;
  CloudFeatures features;
  bool whole = true;  // the whole training cloud, not one of its top-down prefixes
  // The same cloud as a sensor gives it, when what is learnt differs (training views are tilted, see
  // TrainParams::tilt_deg): calibration decides these held-out clouds, as a test cloud would come.
  std::optional<CloudFeatures> as_seen;
  bool augmented = false;  // TrainingCloud::augmented
};
Expected<Model> train_on_features(std::vector<TrainingSample> samples, const TrainParams& params,
                                  const ProgressFn& progress = {}, const CancelFn& cancel = {});

// Inner cross-validation of `method`'s decision stages over params.calibration_folds folds of the
// training objects (`objects[i]` the object of row i, `object_categories` per object); histograms[m] the
// training rows of base method m (what the stages learn), queries[m] the same rows as a sensor gives
// them (what a held-out row is decided on; the same matrix when nothing is tilted), `whole` per row: a
// whole cloud (1) or a top-down prefix (0). prefix_queries[m] row i: row i's own top-down prefix
// (CloudFeatures::top_prefix) whose novelty joins the row's, where has_prefix[i]; has_prefix empty: none.
// The codebooks are the model's own (fitted without labels). Without `measure_novelty` no novelty is
// calibrated (nor any prefix decided): the settle margin, the head's share and the held-out accuracy are
// the same.
// A cancel stops it between inner folds with what it has (the caller then stores nothing).
Calibration calibrate(const ModelImpl& impl, MethodId method, const std::vector<Eigen::MatrixXd>& histograms,
                      const std::vector<Eigen::MatrixXd>& queries, const std::vector<Eigen::MatrixXd>& prefix_queries,
                      const std::vector<uint8_t>& has_prefix, const std::vector<int>& labels,
                      const std::vector<int>& objects, const std::vector<uint8_t>& whole,
                      const std::vector<std::string>& object_categories, int categories, bool measure_novelty,
                      int threads, const CancelFn& cancel = {});

// A failed precondition naming both versions when the model's features were computed differently.
Status check_feature_version(const Model& model);

// The components of the fusion its logistic decision reads (every one but the size-only baseline),
// and a cloud's mapped features from their histograms (`histogram(m)` of each).
std::vector<MethodId> fusion_head_methods(const ModelImpl& impl);
Eigen::VectorXd fusion_head_features(const ModelImpl& impl, const std::function<Eigen::VectorXd(MethodId)>& histogram);
// The mapped features of every row of `histograms` (indexed by MethodId, rows aligned; `rows` empty: all),
// rows shared among `threads` (<= 0: all).
Eigen::MatrixXd fusion_head_rows(const ModelImpl& impl, const std::vector<Eigen::MatrixXd>& histograms,
                                 const std::vector<Eigen::Index>& rows, int threads);
// The fusion's scores: the mean of its components' scores, with `share` of the head's probabilities
// (`probabilities` empty or share 0: the mean alone).
Eigen::VectorXd fused_scores(const Eigen::VectorXd& mean, const Eigen::VectorXd& probabilities, double share);

// Scores of `method` (fusion: the mean of its components' scores, with the head's share).
Eigen::VectorXd method_scores(const ModelImpl& impl, MethodId method, const CloudFeatures& f);

// One component's nearest references: per category, the cloud's distance to it (over its
// `objects` nearest training objects, nearest_objects_distance) and whether its nearest reference is a
// whole training cloud (1) or a top-down prefix (0), whose typical distances differ (Calibration).
struct NearestReferences {
  Eigen::VectorXd distance;
  std::vector<uint8_t> whole;
  double residual = 0;  // StageScores::residual
};
NearestReferences nearest_references(const DecisionStage& stage, StageScores&& scores,
                                     const std::vector<uint8_t>& reference_whole,
                                     const std::vector<uint32_t>& reference_object, const std::vector<int>& objects);

// The scores of `method` with the novelty of each category (empty when `method` was not calibrated
// for novelty: only the model's default method is). The decision's novelty is that of its winner.
struct MethodDecision {
  Eigen::VectorXd scores;
  Eigen::VectorXd novelty;
};
MethodDecision method_decision(const ModelImpl& impl, MethodId method, const CloudFeatures& f);
// Per category, the sum (Calibration::novelty_adds_evidence; else the larger) of two means over the
// components, each over its calibrated scale (Calibration::novelty_scale): the distance to the
// category's nearest reference, and what the stage's PCA leaves out of the histogram; divided by
// `scores` (the decision's, per category) when Calibration::novelty_over_score. Empty when not
// calibrated or the sizes differ.
Eigen::VectorXd category_novelty(const Calibration& c, const std::vector<NearestReferences>& components,
                                 const Eigen::VectorXd& scores);
// A cloud's novelty joined with its top-down prefix's (TrainParams::novelty_prefix): per category, their
// geometric mean. `whole` alone when `prefix` is empty or of another size.
Eigen::VectorXd joint_novelty(const Eigen::VectorXd& whole, const Eigen::VectorXd& prefix);
// novelty, unknown and unknown_reason of `c` (its method and winner set) from `decision` on `f`, at the
// model's default operating point: what classify answers (the lab and sessions' final answer share it).
// The codebook sizes a model can be trained with and read back (train refuses, the reader fails, alike).
Status check_codebook_sizes(const TrainParams& params);
void judge_unknown(const Model& model, const MethodDecision& decision, const CloudFeatures& f, Classification& c);
// judge_unknown after the size rule: warning and outside_learnt_sizes from `points`, the cloud decided
// (after the filters), as classify and a session's final answer judge it.
void judge_cloud(const Model& model, const MethodDecision& decision, const CloudFeatures& f, const Cloud& points,
                 Classification& c);
// Why `method` cannot judge the features at all (a keypoint method with no keypoint); empty if it can.
std::string cannot_judge(MethodId method, const std::vector<MethodId>& components, const CloudFeatures& f);

}  // namespace glimpse
