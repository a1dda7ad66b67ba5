// Private: what a trained Model holds beyond its public summary, and the per-cloud feature pipeline
// shared by train, classify and ScanSession.
#pragma once

#include <array>
#include <chrono>
#include <optional>

#include "glimpse/classifiers.h"
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
};

inline bool uses_keypoints(MethodId m) { return m == MethodId::kBoK || m == MethodId::kBoG || m == MethodId::kKGH; }

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
};

// The methods a model needs computed for `method` (fusion expands to its components).
std::vector<MethodId> component_methods(const ModelImpl& impl, MethodId method);

// What the given methods need of a feature state: keypoint positions and descriptors, and the
// whole-cloud descriptors (USH and size from the points and surfaces, VFH over the surfaces' normals,
// ESF). Shared by whole clouds (cloud_features) and streams (ScanSession).
Expected<CloudFeatures> method_features(const FeatureState& state, const TrainParams& params,
                                        const std::vector<MethodId>& methods, int threads);

// extract() + method_features; keypoints only when one of the methods needs them.
Expected<CloudFeatures> cloud_features(const Cloud& cloud, const TrainParams& params,
                                       const std::vector<MethodId>& methods, int threads,
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
};
Expected<Model> train_on_features(std::vector<TrainingSample> samples, const TrainParams& params,
                                  const ProgressFn& progress = {}, const CancelFn& cancel = {});

// Inner cross-validation of `method`'s decision stages over params.calibration_folds folds of the
// training objects (`objects[i]` the object of row i, `object_categories` per object); histograms[m] the
// training rows of base method m. The codebooks are the model's own (fitted without labels).
Calibration calibrate(const ModelImpl& impl, MethodId method, const std::vector<Eigen::MatrixXd>& histograms,
                      const std::vector<int>& labels, const std::vector<int>& objects,
                      const std::vector<std::string>& object_categories, int categories, int threads);

// A failed precondition naming both versions when the model's features were computed differently.
Status check_feature_version(const Model& model);

// Scores of `method` (fusion: the mean of its components' scores).
Eigen::VectorXd method_scores(const ModelImpl& impl, MethodId method, const CloudFeatures& f);

}  // namespace glimpse
