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

#include "features_impl.h"
#include "glimpse/features.h"
#include "glimpse/model.h"
#include "glimpse/neighbourhoods.h"
#include "glimpse/preprocess.h"
#include "glimpse/scan_filters.h"
#include "model_impl.h"

namespace glimpse {

// ---- Decision: a method's histograms, its decision stages' scores, and whether it is none of the
// categories (novelty, unknown) ------------------------------------------------------------------

Eigen::VectorXd method_histogram(const ModelImpl& impl, MethodId method, const CloudFeatures& f) {
  const TrainParams& p = impl.params;
  const int up_to = p.normalise_up_to_keypoints;
  const bool normalise = p.normalise_histograms && up_to <= 0;
  // sec. 4: counts divided by min(count, count at up_to keypoints).
  auto early = [&](Eigen::VectorXd h, double count, double count_at_up_to) {
    if (up_to > 0 && count > 0) h /= std::min(count, count_at_up_to);
    return h;
  };
  const double n = static_cast<double>(up_to);
  switch (method) {
    case MethodId::kBoK:
      return early(p.bok_soft_words > 1
                       ? soft_bag_of_keypoints(impl.bok, f.descriptors, p.bok_soft_words, normalise)
                       : bag_of_keypoints(keypoint_words(impl.bok, f.descriptors), p.bok_clusters, normalise),
                   static_cast<double>(f.descriptors.size()), n);
    case MethodId::kBoG: {
      const auto graphs = local_graphs(f.positions, keypoint_words(impl.bog, f.descriptors));
      return early(bag_of_graphs(graphs, impl.graphs, normalise), static_cast<double>(graphs.size()), n);
    }
    case MethodId::kKGH: {
      const double k = static_cast<double>(f.positions.size());
      return early(keypoint_global_histogram(f.positions, keypoint_words(impl.kgh, f.descriptors), p.kgh_clusters,
                                             p.kgh_distance_bins, impl.kgh_max_distance_m, normalise),
                   k * (k - 1), n * (n - 1));
    }
    case MethodId::kVFH: return f.vfh ? Eigen::VectorXd(f.vfh->cast<double>()) : Eigen::VectorXd::Zero(kVfhSize);
    case MethodId::kESF: return f.esf ? Eigen::VectorXd(f.esf->cast<double>()) : Eigen::VectorXd::Zero(kEsfSize);
    case MethodId::kUSH:
      return f.ush ? Eigen::VectorXd(f.ush->cast<double>()) : Eigen::VectorXd::Zero(kUprightHistogramSize);
    case MethodId::kSize: return f.size ? Eigen::VectorXd(f.size->cast<double>()) : Eigen::VectorXd::Zero(kVisibleSizeSize);
    case MethodId::kFusion: break;
  }
  return {};
}

std::vector<MethodId> fusion_head_methods(const ModelImpl& impl) {
  std::vector<MethodId> parts = component_methods(impl, MethodId::kFusion);
  std::erase(parts, MethodId::kSize);
  return parts;
}

Eigen::VectorXd fusion_head_features(const ModelImpl& impl, const std::function<Eigen::VectorXd(MethodId)>& histogram) {
  std::vector<Eigen::VectorXd> histograms;
  for (MethodId m : fusion_head_methods(impl)) histograms.push_back(histogram(m));
  return additive_chi2_features(histograms, impl.params.fusion_head.sample_steps, impl.params.fusion_head.sample_interval);
}

Eigen::MatrixXd fusion_head_rows(const ModelImpl& impl, const std::vector<Eigen::MatrixXd>& histograms,
                                 const std::vector<Eigen::Index>& rows, int threads) {
  const std::vector<MethodId> parts = fusion_head_methods(impl);
  if (parts.empty()) return {};
  const Eigen::Index n = rows.empty() ? histograms[static_cast<size_t>(parts.front())].rows() : static_cast<Eigen::Index>(rows.size());
  auto features = [&](Eigen::Index i) {
    const Eigen::Index r = rows.empty() ? i : rows[static_cast<size_t>(i)];
    return fusion_head_features(impl, [&](MethodId m) { return Eigen::VectorXd(histograms[static_cast<size_t>(m)].row(r).transpose()); });
  };
  if (n == 0) return {};
  const Eigen::VectorXd first = features(0);
  Eigen::MatrixXd out(n, first.size());
  out.row(0) = first.transpose();
#pragma omp parallel for num_threads(threads > 0 ? threads : omp_get_max_threads()) schedule(static, 64)
  for (Eigen::Index i = 1; i < n; ++i) out.row(i) = features(i).transpose();
  return out;
}

Eigen::VectorXd fused_scores(const Eigen::VectorXd& mean, const Eigen::VectorXd& probabilities, double share) {
  if (!(share > 0) || probabilities.size() != mean.size()) return mean;
  return (1 - share) * mean + share * probabilities;
}

namespace {
// The mean of `parts`' decision stages' scores of `f`; with `nearest`, each component's nearest
// references too.
Eigen::VectorXd component_scores(const ModelImpl& impl, const std::vector<MethodId>& parts, const CloudFeatures& f,
                                 std::vector<NearestReferences>* nearest) {
  const Calibration& cal = impl.calibration;
  Eigen::VectorXd scores;
  for (size_t j = 0; j < parts.size(); ++j) {
    const MethodId m = parts[j];
    // sec. 4: early in the exploration (fewer than normalise_up_to_keypoints keypoints) the words'
    // proportions are compared, the references' too; later the counts.
    const int up_to = impl.params.normalise_up_to_keypoints;
    const bool early = up_to > 0 && (m == MethodId::kBoK || m == MethodId::kKGH) &&
                       f.descriptors.size() < static_cast<size_t>(up_to);
    StageScores s = decide_with_distances(*impl.stages[static_cast<int>(m)], method_histogram(impl, m, f), early);
    scores = scores.size() ? Eigen::VectorXd(scores + s.scores) : s.scores;
    if (nearest) {
      const std::vector<uint32_t> none;
      const std::vector<uint32_t>& objects = j < cal.reference_object.size() ? cal.reference_object[j] : none;
      nearest->push_back(nearest_references(*impl.stages[static_cast<int>(m)], std::move(s), cal.reference_whole[j],
                                            objects, cal.novelty_objects));
    }
  }
  return scores / static_cast<double>(std::max<size_t>(1, parts.size()));
}

// A method's mean score over its components' decision stages and, with `with_novelty` and a calibrated
// novelty, how novel the cloud is to each category (joined by its top-down prefix's, as calibrated).
MethodDecision stage_decision(const ModelImpl& impl, MethodId method, const CloudFeatures& f, bool with_novelty) {
  const std::vector<MethodId> parts = component_methods(impl, method);
  const Calibration& cal = impl.calibration;
  const bool calibrated =
      with_novelty && cal.method == method && !cal.novelty_scale.empty() && cal.reference_whole.size() == parts.size();
  MethodDecision out;
  std::vector<NearestReferences> nearest;
  out.scores = component_scores(impl, parts, f, calibrated ? &nearest : nullptr);
  // Novelty from the nearest references and their scores alone: the logistic decision is as sure of a
  // cloud far from everything learnt as of a known one (a logistic score grows away from the boundary).
  if (!calibrated) return out;
  out.novelty = category_novelty(cal, nearest, out.scores);
  if (impl.params.novelty_prefix > 0 && f.top_prefix) {
    std::vector<NearestReferences> prefix_nearest;
    const Eigen::VectorXd prefix_scores = component_scores(impl, parts, *f.top_prefix, &prefix_nearest);
    out.novelty = joint_novelty(out.novelty, category_novelty(cal, prefix_nearest, prefix_scores));
  }
  return out;
}
}  // namespace

MethodDecision method_decision(const ModelImpl& impl, MethodId method, const CloudFeatures& f) {
  MethodDecision out = stage_decision(impl, method, f, !impl.novelty);
  // Trained with augmented clouds: novelty from the model of the clouds given as they are.
  if (impl.novelty) out.novelty = stage_decision(*impl.novelty, method, f, true).novelty;
  const double share = impl.calibration.fusion_head_share;
  if (method == MethodId::kFusion && impl.fusion_head && share > 0) {
    const Eigen::VectorXd features =
        fusion_head_features(impl, [&](MethodId m) { return method_histogram(impl, m, f); });
    out.scores = fused_scores(out.scores, chi2_logistic_probabilities(*impl.fusion_head, features), share);
  }
  return out;
}

Eigen::VectorXd method_scores(const ModelImpl& impl, MethodId method, const CloudFeatures& f) {
  return method_decision(impl, method, f).scores;
}

TrainParams method_feature_params(const ModelImpl& impl, MethodId method) {
  TrainParams p = impl.params;
  const Calibration& c = novelty_calibration(impl);
  if (c.method != method || c.novelty_scale.empty()) p.novelty_prefix = 0;
  return p;
}

std::string cannot_judge(MethodId method, const std::vector<MethodId>& components, const CloudFeatures& f) {
  // A keypoint histogram of too few keypoints is empty (BoG's graphs join 4 keypoints, KGH's pairs 2):
  // its nearest category is an accident. Fusion judges as long as one component can.
  auto blind = [&](MethodId m) {
    const size_t k = f.positions.size();
    return (m == MethodId::kBoK && k == 0) || (m == MethodId::kBoG && k < 4) || (m == MethodId::kKGH && k < 2);
  };
  if (components.empty() || !std::all_of(components.begin(), components.end(), blind)) return {};
  return std::to_string(f.positions.size()) + " keypoint" + (f.positions.size() == 1 ? "" : "s") + ": " +
         method_name(method) + " cannot judge this cloud (an empty histogram)";
}

namespace {

// `unknown` and its reason from the novelty at `threshold` (NaN: no novelty threshold, never unknown).
void judge_novelty(Classification& c, double threshold, double known_acceptance) {
  c.unknown = std::isfinite(threshold) && std::isfinite(c.novelty) && c.novelty > threshold;
  c.unknown_reason.clear();
  if (c.outside_learnt_sizes) {  // the reason a person can act on (a unit), whatever the novelty
    c.unknown = true;
    c.unknown_reason = "size far outside what the model learnt: " + c.warning;
  }
  if (!c.unknown || !c.unknown_reason.empty()) return;
  char why[200];
  std::snprintf(why, sizeof why,
                "novelty %.2f above %.2f, the threshold accepting %.1f %% of known clouds (held out in training)",
                c.novelty, threshold, 100 * known_acceptance);
  c.unknown_reason = why;
}

}  // namespace

void judge_unknown(const Model& model, const MethodDecision& decision, const CloudFeatures& f, Classification& c) {
  if (std::string why = cannot_judge(c.method, component_methods(*model.impl, c.method), f); !why.empty()) {
    c.novelty = std::numeric_limits<double>::quiet_NaN();
    c.unknown = true;
    c.unknown_reason = std::move(why);
    return;
  }
  c.category_novelty.assign(decision.novelty.data(), decision.novelty.data() + decision.novelty.size());
  if (decision.novelty.size() && c.winner >= 0) c.novelty = decision.novelty[c.winner];
  (void)set_known_acceptance(model, c, 0);  // 0 (the default) is always valid
}

void judge_cloud(const Model& model, const MethodDecision& decision, const CloudFeatures& f, const Cloud& points,
                 Classification& c) {
  c.warning = size_warning(model.stats, points);
  c.outside_learnt_sizes = !c.warning.empty();
  judge_unknown(model, decision, f, c);
}

Status set_known_acceptance(const Model& model, Classification& c, double known_acceptance) {
  if (!(known_acceptance >= 0 && known_acceptance <= 1))
    return invalid_argument("known acceptance must be in (0, 1] (0: the model's default), not " +
                            std::to_string(known_acceptance));
  if (c.unknown && !std::isfinite(c.novelty)) return {};  // the method cannot judge the cloud at all
  const Calibration& cal = novelty_calibration(model);
  const double a = known_acceptance > 0 ? known_acceptance : cal.known_acceptance;
  judge_novelty(c, cal.method == c.method ? novelty_threshold(cal, a) : std::numeric_limits<double>::quiet_NaN(), a);
  return {};
}

// ---- Classification ----------------------------------------------------------------------------

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

// classify_fused once the points are clean.
Expected<Classification> classify_filtering(const Model& model, const Cloud& cloud,
                                            const std::vector<std::optional<Vec3>>& point_sensors, MethodId m,
                                            const CancelFn& cancel) {
  // Several views of a filtering model's scan are decided one by one (classify_views.cpp); when none can
  // be decided alone, the fused scan is.
  if (model.impl->params.filter_scans && !point_sensors.empty()) {
    if (const auto views = scan_views(cloud, point_sensors); views.size() > 1) {
      auto joined = classify_views(model, cloud, point_sensors, views, m, cancel);
      if (joined.ok() || joined.error().code == ErrorCode::kCancelled) return joined;
    }
  }
  return classify_scan(model, cloud, point_sensors, m, cancel);
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
  if (model.impl->params.filter_scans) {
    // The filters meet the points a session keeps (Session::add_raw): non-finite points and duplicates
    // out first, so a stray point copied many times (a depth camera's invalid pixels) is still a stray
    // point, and a scan streamed ends as the same scan classified whole.
    Cloud kept;
    kept.sensor = cloud.sensor;
    std::vector<std::optional<Vec3>> kept_sensors;
    DuplicateFilter duplicates(model.impl->params.features.duplicate_tolerance_m, cloud.points.size());
    clean_into(cloud, point_sensors, duplicates, kept, point_sensors.empty() ? nullptr : &kept_sensors);
    // Nothing finite: the features' own error says how many points were NaN/Inf.
    if (!kept.points.empty() && kept.points.size() < cloud.points.size())
      return classify_filtering(model, kept, kept_sensors, m, cancel);
  }
  return classify_filtering(model, cloud, point_sensors, m, cancel);
}

Expected<Classification> classify_scan(const Model& model, const Cloud& cloud,
                                       const std::vector<std::optional<Vec3>>& point_sensors, MethodId m,
                                       const CancelFn& cancel) {
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
  const TrainParams params = method_feature_params(impl, m);
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
  judge_cloud(model, decision, *f, points, c);  // after the filters: a stray point is not the object's size
  c.points = f->points;
  c.keypoints = f->positions.size();
  c.filters = report;
  return c;
}

}  // namespace glimpse
