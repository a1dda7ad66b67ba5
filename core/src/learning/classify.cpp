// Classification of one cloud, or of a scan fused from several sensor positions: the scan filters the
// model recorded, the features of its methods, the decision and whether it is none of the learnt
// categories (sec. 4).
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "glimpse/learning/classify.h"

#include "glimpse/clock.h"
#include "glimpse/features/local_features.h"
#include "glimpse/features/method_features.h"
#include "glimpse/geometry/clean.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/scan_filters.h"
#include "glimpse/learning/model.h"
#include "glimpse/learning/model_internals.h"
#include "glimpse/learning/novelty.h"
#include "glimpse/learning/probabilities.h"
#include "glimpse/learning/scores.h"

namespace glimpse {

Status check_feature_version(const Model& model) {
  if (model.feature_version == kFeaturePipelineVersion) return {};
  return failed_precondition("the model was trained with feature pipeline version " +
                             std::to_string(model.feature_version) + ", this build computes version " +
                             std::to_string(kFeaturePipelineVersion) + ": its references do not match new features; retrain it");
}

Status check_trained_for(const Model& model, MethodId method) {
  if (std::find(model.methods.begin(), model.methods.end(), method) != model.methods.end()) return {};
  return failed_precondition(std::string("the model was not trained for method '") + method_name(method) + "'");
}

namespace {

// The sensor of each filtered point: that of the nearest raw point (itself, or for a voxel centroid a
// point of its voxel).
std::vector<std::optional<Vec3>> sensors_after_filters(const Cloud& filtered, const Cloud& raw,
                                                       const std::vector<std::optional<Vec3>>& raw_sensors) {
  std::vector<std::optional<Vec3>> out;
  out.reserve(filtered.points.size());
  const KdTree tree(raw.points);
  std::vector<Neighbour> near;
  for (const Vec3& p : filtered.points) {
    tree.nearest(p, 1, near);
    out.push_back(near.empty() ? filtered.sensor : raw_sensors[near[0].index]);
  }
  return out;
}

// classify_fused once the points are clean.
Expected<Classification> classify_by_views(const Model& model, const Cloud& cloud,
                                            const std::vector<std::optional<Vec3>>& point_sensors, MethodId m,
                                            const CancelFn& cancel) {
  // Several views of a filtering model's scan are decided one by one (classify_views.cpp); when none can
  // be decided alone, the fused scan is.
  if (model.impl->params.filter_scans && !point_sensors.empty()) {
    if (const auto views = scan_views(cloud, point_sensors); views.size() > 1) {
      auto joined = classify_views_apart(model, cloud, point_sensors, views, m, cancel);
      if (joined.ok() || joined.error().code == ErrorCode::kCancelled) return joined;
    }
  }
  return classify_one_view(model, cloud, point_sensors, m, cancel);
}

}  // namespace

Expected<Classification> classify(const Model& model, const Cloud& cloud, std::optional<MethodId> method,
                                  const CancelFn& cancel) {
  return classify_fused(model, cloud, {}, method, cancel);
}

Expected<Classification> classify_fused(const Model& model, const Cloud& cloud,
                                        const std::vector<std::optional<Vec3>>& point_sensors,
                                        std::optional<MethodId> method, const CancelFn& cancel) {
  if (!model.impl) return failed_precondition("the model is not trained");
  if (Status s = check_feature_version(model); !s.ok()) return s.error();
  const MethodId m = method.value_or(model.default_method);
  if (Status s = check_trained_for(model, m); !s.ok()) return s.error();
  if (!point_sensors.empty() && point_sensors.size() != cloud.points.size())
    return invalid_argument("point_sensors must name one sensor per point");
  if (model.impl->params.filter_scans) {
    // The filters meet the points a session keeps (Session::add_raw): non-finite points and duplicates
    // out first, so a stray point copied many times (a depth camera's invalid pixels) is still a stray
    // point, and a scan streamed ends as the same scan classified whole.
    Cloud kept;
    kept.sensor = cloud.sensor;
    kept.frame = cloud.frame;
    std::vector<std::optional<Vec3>> kept_sensors;
    DuplicateFilter duplicates(model.impl->params.features.duplicate_tolerance_m, cloud.points.size());
    clean_into(cloud, point_sensors, duplicates, kept, point_sensors.empty() ? nullptr : &kept_sensors);
    // Nothing finite: the features' own error says how many points were NaN/Inf.
    if (!kept.points.empty() && kept.points.size() < cloud.points.size())
      return classify_by_views(model, kept, kept_sensors, m, cancel);
  }
  return classify_by_views(model, cloud, point_sensors, m, cancel);
}

Expected<Classification> classify_one_view(const Model& model, const Cloud& cloud,
                                       const std::vector<std::optional<Vec3>>& point_sensors, MethodId m,
                                       const CancelFn& cancel) {
  const ModelImpl& impl = *model.impl;
  const auto t0 = std::chrono::steady_clock::now();
  if (!impl.params.filter_scans) return decide_after_filters(model, cloud, point_sensors, nullptr, {}, m, t0, cancel);
  ScanFilterReport report;
  const Cloud filtered = filter_scan(cloud, impl.params.filters, &report);
  return decide_after_filters(model, cloud, point_sensors, &filtered, report, m, t0, cancel);
}

Expected<Classification> decide_after_filters(const Model& model, const Cloud& cloud,
                                           const std::vector<std::optional<Vec3>>& point_sensors,
                                           const Cloud* filtered, const ScanFilterReport& report, MethodId m,
                                           std::chrono::steady_clock::time_point t0, const CancelFn& cancel) {
  const ModelImpl& impl = *model.impl;
  const Cloud& points = filtered ? *filtered : cloud;
  const std::vector<MethodId> methods = component_methods(impl, m);
  const MethodFeatureParams params = feature_params_for(impl, m);
  Expected<CloudFeatures> f = failed_precondition("no features");
  if (point_sensors.empty() || one_sensor(point_sensors)) {
    Cloud one;
    const Cloud* in = &points;
    if (!point_sensors.empty() && point_sensors.front() != points.sensor) {
      one = points;
      one.sensor = point_sensors.front();
      in = &one;
    }
    f = cloud_features(*in, params, methods, impl.params.threads, cancel);
  } else {
    FeatureParams fp = impl.params.features;
    fp.surface.threads = impl.params.threads;
    fp.find_keypoints = std::any_of(methods.begin(), methods.end(), uses_keypoints);
    auto state =
        extract_fused(points, filtered ? sensors_after_filters(points, cloud, point_sensors) : point_sensors, fp, cancel);
    if (!state.ok()) return state.error();
    f = method_features(*state, params, methods, impl.params.threads);
  }
  if (!f.ok()) return f.error();
  if (cancel && cancel()) return cancelled("classification cancelled");
  Classification c;
  c.feature_ms = ms_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  const MethodDecision decision = method_decision(impl, m, *f);
  const Eigen::VectorXd& scores = decision.scores;
  c.decision_ms = ms_since(t1);
  c.method = m;
  c.categories = model.categories;
  c.scores.assign(scores.data(), scores.data() + scores.size());
  c.winner = argmax(scores);
  c.probabilities = calibrated_probabilities(impl.calibration, m, c.scores);
  judge_cloud(model, decision, *f, points, c);  // after the filters: a stray point is not the object's size
  c.points = f->points;
  c.keypoints = f->positions.size();
  c.filters = report;
  return c;
}

}  // namespace glimpse
