// A trained model: everything training produces (codebooks, PCA bases, centres, category names,
// statistics), the train/classify entry points, and its versioned byte format (sec. 3.3, sec. 4).
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/features/methods.h"
#include "glimpse/geometry/frame_cut.h"
#include "glimpse/geometry/scan_filters.h"

namespace glimpse {

struct TrainingCloud {
  std::string category;
  std::string object_id;  // views of one object share it (cross-validation splits by object)
  Cloud cloud;
  // A view made to widen what the decision learns (a simulated sensor's view of an object also given as
  // it is, or the procedural zoo's objects added to real ones): learnt like any cloud, but what "unknown"
  // measures a cloud against is learnt from the other clouds alone (ModelImpl::novelty).
  bool augmented = false;
};

struct TrainingProgress {
  std::string stage;  // "features", "codebooks", "centres", "calibration", "novelty", "done"
  size_t done = 0;
  size_t total = 0;
};
using ProgressFn = std::function<void(const TrainingProgress&)>;

struct TrainingSummary {
  size_t clouds = 0;
  size_t objects = 0;
  size_t keypoints = 0;
  std::vector<std::string> categories;
  std::vector<size_t> clouds_per_category;
  double seconds = 0;
  // The largest bounding-box extent of the clouds learnt (views and prefixes), smallest and largest, m:
  // what sizes the model knows, so a cloud far outside them (a scan in millimetres) gets a warning.
  float min_extent_m = 0, max_extent_m = 0;
};

// The version of the feature pipeline (cleaning, radii, surfaces, keypoints, descriptors, histograms):
// raised whenever a change moves the numbers a cloud's features come out as. A model stores the version
// it was trained with; classifying with a model of another version is refused (its references would be
// compared with features computed differently).
inline constexpr uint32_t kFeaturePipelineVersion = 3;

inline constexpr size_t kNoveltyQuantiles = 201;  // every half percent of known acceptance (Calibration)

// What a model measured of its own decisions on held-out folds of its training set (inner
// cross-validation by object, TrainParams::calibration_folds), so no threshold is set on the clouds it
// is judged on.
struct Calibration {
  MethodId method = MethodId::kFusion;  // the method measured: the model's default
  // The smallest margin between the best two scores at which held-out decisions were at least
  // TrainParams::settle_precision right; a streamed decision of `method` settles there. 0: not
  // calibrated (too few objects), sessions use SessionParams::full_margin.
  double settle_margin = 0;
  size_t held_out = 0;           // held-out decisions (views and prefixes) it was measured on
  double held_out_accuracy = 0;  // their share right
  // Novelty ("none of these"): per component of `method` (fusion: each of its methods), category and
  // kind of nearest reference (index 2 x category + 1 for a whole training cloud, + 0 for a top-down
  // prefix), the median distance from held-out clouds decided as that category to its nearest
  // reference; last (+ 0 prefix, + 1 whole, by the winner's nearest reference), the median of what the
  // stage's PCA leaves out of held-out histograms. A cloud's
  // novelty for a category is the sum (novelty_adds_evidence) of two means over the components: its
  // distance to the category's nearest reference over that median, and what PCA leaves out of its
  // histogram over that median. Known clouds come out near 2, clouds of nothing learnt above. Empty: not
  // calibrated (a model of format 3 or older, or too few objects).
  std::vector<std::vector<double>> novelty_scale;
  // Per component, per reference of the model's decision stage: 1 a whole training cloud, 0 a prefix
  // (empty: every reference whole, as for decision rules whose references are centres).
  std::vector<std::vector<uint8_t>> reference_whole;
  // A cloud's distance to a category is the mean over the category's novelty_objects[category] nearest
  // training objects of its distance to each one's nearest reference: TrainParams::novelty_objects, or
  // fewer where an inner training fold held fewer objects of the category (the count the quantiles were
  // taken with). reference_object: per component, per reference of the model's decision stage, its
  // training object (0, 1, ...). A model of format 5 or older reads none of either: the nearest reference
  // alone, what its quantiles were taken on.
  std::vector<int> novelty_objects;
  std::vector<std::vector<uint32_t>> reference_object;
  // The held-out known clouds' novelty (of their decided category) at known acceptance 0, 1/(n-1), ...,
  // 1 (n = kNoveltyQuantiles): the threshold accepting a share a of known clouds is its a-quantile.
  std::vector<double> novelty_quantiles;
  // The novelty of a category is divided by the decision's score of that category (format 5 on): a
  // cloud both far from what was learnt and torn between categories is more novel than one far but
  // plainly of one. False: a model of format 4, whose quantiles were taken without it.
  bool novelty_over_score = true;
  // The two means above are added (format 9 on): a cloud somewhat far from every reference and somewhat
  // outside what training histograms span is more novel than one as far on one count alone. False: the
  // larger of the two, as a model of format 8 or older took its quantiles.
  bool novelty_adds_evidence = true;
  double known_acceptance = 0.95;  // the model's default operating point (TrainParams::known_acceptance)
  double novelty_threshold = std::numeric_limits<double>::quiet_NaN();  // at known_acceptance; NaN: none
  // The share of the fusion's logistic decision in its scores (TrainParams::fusion_head_shares), chosen
  // on the held-out decisions above; 0: none (a model of format 6 or older, or no head).
  double fusion_head_share = 0;
  // The temperature that turns the held-out decisions' scores (at the head's share) into probabilities
  // with the least log loss (probabilities.h); 0: none (a model of format 10 or older, or too few objects).
  double probability_temperature = 0;
  // The lowest winner's probability (at that temperature) at which the held-out decisions were at least
  // TrainParams::settle_precision right: where a streamed decision in probabilities settles
  // (SessionParams::settle_on_probability). 0: none.
  double settle_probability = 0;
};

struct ModelImpl;  // codebooks, bases, centres: defined in model_internals.h

struct TrainParams;  // defined in train_params.h: features, codebooks, decision; defaults there

struct Model {
  std::vector<std::string> categories;
  std::vector<MethodId> methods;  // methods this model can classify with
  MethodId default_method = MethodId::kFusion;
  uint32_t feature_version = kFeaturePipelineVersion;  // models of format 1-2 read as version 1
  TrainingSummary stats;
  std::shared_ptr<const ModelImpl> impl;  // immutable after training; shared by sessions/threads
};

struct Classification {
  MethodId method = MethodId::kFusion;
  std::vector<std::string> categories;
  std::vector<double> scores;  // one per category, in [0, 1], summing to 1; higher is more likely
  // The scores as calibrated probabilities (Calibration::probability_temperature): of the views the
  // model held out in training, those given p were right p of the time. Empty: not calibrated (a method
  // other than the model's default, or a model of format 10 or older).
  std::vector<double> probabilities;
  int winner = -1;             // index into categories
  size_t points = 0;           // after cleaning
  size_t keypoints = 0;
  double feature_ms = 0;
  double decision_ms = 0;
  std::string warning;  // for a person: e.g. the cloud is far larger than anything the model learnt
  ScanFilterReport filters;  // what the scan filters took (all zero when the model does not filter)
  // "None of these": the winner stays the nearest known category; unknown when its novelty (see
  // Calibration) is above the threshold of the model's operating point, or when the method cannot
  // judge the cloud (a keypoint method with no keypoint), with the reason and a NaN novelty. NaN
  // novelty otherwise: the method was not calibrated (only the model's default method is).
  double novelty = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> category_novelty;  // per category (a stream smooths them); empty: not calibrated
  bool unknown = false;
  std::string unknown_reason;
  // The cloud spans more than 4 x the largest or less than a quarter of the smallest extent the model
  // learnt (`warning` says which): unknown at every operating point, whatever its novelty. A cloud the
  // camera's frame cuts is never too small (it is part of its object).
  bool outside_learnt_sizes = false;
  // The edges of the camera's frame the object reaches (after the filters; none without a frame): the
  // answer is of the part the frame lets through.
  FrameCut frame_cut;
};

// The novelty above which a decision is "unknown" when `known_acceptance` (in (0, 1]) of the held-out
// known clouds are to be accepted; NaN when the calibration has no novelty (nothing is then unknown
// but what a method cannot judge).
double novelty_threshold(const Calibration& calibration, double known_acceptance);

// Re-decides `unknown` at another operating point (known acceptance in (0, 1]; 0: the model's default);
// the winner and scores stay. A decision the method cannot judge stays unknown. Invalid argument
// outside [0, 1].
Status set_known_acceptance(const Model& model, Classification& classification, double known_acceptance);

// A warning when the cloud's largest extent is more than 4x outside the extents the model learnt
// ("the cloud spans 1700 m, the model knows 0.03-2.1 m objects: millimetres?"); empty otherwise. Never
// too small when the camera's frame cuts the cloud (geometry/frame_cut.h).
std::string size_warning(const TrainingSummary& stats, const Cloud& cloud);

// Fold (0..folds-1) of every object: per category, the objects are shuffled (seeded) and dealt round
// robin, so each fold holds floor or ceil(n / folds) objects of every category; each category starts
// where the one before it ended. The evaluation's cross-validation (training's own calibration deals
// with calibration_folds, calibration.h).
std::vector<int> stratified_folds(const std::vector<std::string>& object_categories, int folds, uint64_t seed);

// The lowest margin at which (margin, right) decisions reach `precision` (counting from min_count
// decisions on); above every margin when they never do, 0 for fewer than min_count decisions.
double settle_margin(std::vector<std::pair<double, bool>> decisions, double precision, size_t min_count);

// The model's calibration (all zero for an untrained model).
const Calibration& calibration(const Model& model);
// The calibration its novelty and threshold come from: its novelty model's when some training clouds
// were augmented (TrainingCloud::augmented), else calibration(model).
const Calibration& novelty_calibration(const Model& model);

// A failed precondition when the model has no decision for `method` ("the model was not trained for
// method 'esf'"): Classify, ClassifyBatch and sessions refuse such a call alike.
Status check_trained_for(const Model& model, MethodId method);

Expected<Model> train(const std::vector<TrainingCloud>& data, const TrainParams& params,
                      const ProgressFn& progress = {}, const CancelFn& cancel = {});

Expected<Classification> classify(const Model& model, const Cloud& cloud,
                                  std::optional<MethodId> method = std::nullopt,
                                  const CancelFn& cancel = {});

// A scan fused from several sensor positions (a stream's chunks): point_sensors names, per point, the
// sensor that saw it (empty: cloud.sensor for all). A model that filters its scans (the default)
// decides a scan of several views view by view: the points whose sensors look from within 30 degrees
// of one another (seen from the scan's centroid) are one view, each view is classified as a single
// view (every model learns single views; a cloud of every side of an object is unlike any of them),
// and the answers are joined (the mean of their scores and novelties). Within a view, and for a model
// without filters on the whole scan, the filters see all the points and each point kept faces its own
// sensor (a voxel centroid the sensor of the nearest point it came from). With one sensor for every
// point this is classify() of the cloud with that sensor.
Expected<Classification> classify_fused(const Model& model, const Cloud& cloud,
                                        const std::vector<std::optional<Vec3>>& point_sensors,
                                        std::optional<MethodId> method = std::nullopt, const CancelFn& cancel = {});

// Versioned, little-endian byte format with a checksum; deserialize rejects truncated or corrupt input.
std::vector<uint8_t> serialize(const Model& model);
Expected<Model> deserialize(std::span<const uint8_t> bytes);

}  // namespace glimpse
