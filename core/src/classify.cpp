// Classification of one cloud, or of a scan fused from several sensor positions: the scan filters the
// model recorded, the features of its methods, the decision (sec. 4).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "features_impl.h"
#include "glimpse/features.h"
#include "glimpse/model.h"
#include "glimpse/neighbourhoods.h"
#include "glimpse/scan_filters.h"
#include "model_impl.h"

namespace glimpse {

std::string size_warning(const TrainingSummary& stats, const Cloud& cloud) {
  if (!(stats.max_extent_m > 0) || cloud.points.empty()) return {};
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (const Vec3& p : cloud.points)
    if (p.allFinite()) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const float extent = (hi - lo).maxCoeff();
  if (!std::isfinite(extent)) return {};
  char known[96];
  std::snprintf(known, sizeof known, "the model knows %.2g-%.2g m objects", stats.min_extent_m, stats.max_extent_m);
  char buf[256];
  if (extent > 4 * stats.max_extent_m) {
    const char* unit = extent > 300 * stats.max_extent_m ? "millimetres" : extent > 30 * stats.max_extent_m ? "centimetres" : "another unit";
    std::snprintf(buf, sizeof buf, "the cloud spans %.3g m, %s: %s? Clouds are in metres", extent, known, unit);
    return buf;
  }
  if (extent < stats.min_extent_m / 4) {
    std::snprintf(buf, sizeof buf, "the cloud spans only %.3g m, %s: another unit (clouds are in metres)?", extent, known);
    return buf;
  }
  return {};
}

Status check_feature_version(const Model& model) {
  if (model.feature_version == kFeaturePipelineVersion) return {};
  return failed_precondition("the model was trained with feature pipeline version " +
                             std::to_string(model.feature_version) + ", this build computes version " +
                             std::to_string(kFeaturePipelineVersion) + ": its references do not match new features; retrain it");
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
  if (std::find(model.methods.begin(), model.methods.end(), m) == model.methods.end())
    return failed_precondition(std::string("the model was not trained for method '") + method_name(m) + "'");
  if (!point_sensors.empty() && point_sensors.size() != cloud.points.size())
    return invalid_argument("point_sensors must name one sensor per point");
  const ModelImpl& impl = *model.impl;
  const auto t0 = std::chrono::steady_clock::now();
  if (!impl.params.filter_scans) return classify_filtered(model, cloud, point_sensors, nullptr, {}, m, t0, cancel);
  ScanFilterReport report;
  const Cloud filtered = filter_scan(cloud, impl.params.filters, &report);
  return classify_filtered(model, cloud, point_sensors, &filtered, report, m, t0, cancel);
}

Expected<Classification> classify_filtered(const Model& model, const Cloud& cloud,
                                           const std::vector<std::optional<Vec3>>& point_sensors,
                                           const Cloud* filtered, const ScanFilterReport& report, MethodId m,
                                           std::chrono::steady_clock::time_point t0, const CancelFn& cancel) {
  const ModelImpl& impl = *model.impl;
  const Cloud& points = filtered ? *filtered : cloud;
  const std::vector<MethodId> methods = component_methods(impl, m);
  Expected<CloudFeatures> f = failed_precondition("no features");
  if (point_sensors.empty() || one_sensor(point_sensors)) {
    Cloud one;
    const Cloud* in = &points;
    if (!point_sensors.empty() && point_sensors.front() != points.sensor) {
      one = points;
      one.sensor = point_sensors.front();
      in = &one;
    }
    f = cloud_features(*in, impl.params, methods, impl.params.threads, cancel);
  } else {
    FeatureParams fp = impl.params.features;
    fp.surface.threads = impl.params.threads;
    fp.find_keypoints = std::any_of(methods.begin(), methods.end(), uses_keypoints);
    auto state =
        extract_fused(points, filtered ? sensors_after_filters(points, cloud, point_sensors) : point_sensors, fp, cancel);
    if (!state.ok()) return state.error();
    f = method_features(*state, impl.params, methods, impl.params.threads);
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
  judge_unknown(model, decision, *f, c);
  c.points = f->points;
  c.keypoints = f->positions.size();
  c.warning = size_warning(model.stats, cloud);
  c.filters = report;
  return c;
}

}  // namespace glimpse
