// Test views as real sensors take them (views/sensors.h) and the robustness matrix: the trained fold models
// classify each tested object's views under each scan condition, after the same filters.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "protocol.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/exploration.h"

namespace glimpse {

std::vector<ScanCondition> robustness_conditions(std::string_view matrix) {
  std::vector<ScanCondition> out;
  if (matrix == "none") return out;
  out.push_back({});  // ideal, through the filters
  auto ideal_density = [](double d) { ScanCondition c; c.density = d; return c; };
  auto tilt = [](float t) { ScanCondition c; c.tilt_deg = t; return c; };
  auto sensor = [](SensorKind k, float d, float e, int beams = 16) {
    ScanCondition c;
    c.sensor = k, c.distance_m = d, c.elevation_deg = e, c.beams = beams;
    return c;
  };
  ScanCondition residue = sensor(SensorKind::kDepthCamera, 2.f, 30.f);
  residue.floor = true, residue.outliers = 0.02;
  if (matrix == "small") {
    out.push_back(ideal_density(0.25));
    out.push_back(ideal_density(4));
    out.push_back(tilt(5));
    out.push_back(sensor(SensorKind::kDepthCamera, 2.f, 30.f));
    out.push_back(residue);
    out.push_back(sensor(SensorKind::kLidar, 10.f, 5.f));
    return out;
  }
  if (matrix == "sensors") {  // the poses real scanners take
    for (float d : {0.8f, 1.f, 2.f, 3.f, 4.f})
      for (float e : {-10.f, 0.f, 15.f, 30.f, 45.f, 60.f}) out.push_back(sensor(SensorKind::kDepthCamera, d, e));
    for (int beams : {16, 32, 64})
      for (float d : {5.f, 10.f, 20.f}) out.push_back(sensor(SensorKind::kLidar, d, 5.f, beams));
    return out;
  }
  if (matrix != "full") return {};
  for (double d : {0.25, 0.5, 2.0, 4.0}) out.push_back(ideal_density(d));
  for (float t : {2.f, 5.f, 10.f}) out.push_back(tilt(t));
  for (float d : {1.f, 2.f, 3.f})
    for (float e : {0.f, 15.f, 30.f, 45.f}) out.push_back(sensor(SensorKind::kDepthCamera, d, e));
  ScanCondition floor = sensor(SensorKind::kDepthCamera, 2.f, 30.f);
  floor.floor = true;
  out.push_back(floor);
  ScanCondition outliers = sensor(SensorKind::kDepthCamera, 2.f, 30.f);
  outliers.outliers = 0.05;
  out.push_back(outliers);
  out.push_back(residue);
  for (float d : {5.f, 10.f, 15.f}) out.push_back(sensor(SensorKind::kLidar, d, 5.f));
  return out;
}

namespace eval_internal {

namespace {

// One view of the matrix under a condition: its points before and after the scan filters, and whether a
// ground plane was removed.
struct ConditionView {
  size_t raw_points = 0, kept_points = 0;
  bool ground = false;
};

// Tested view v taken under `condition`, filtered to its fold model's density and decided by that model
// at each of `stages` (cut at the same share of its points as of the ideal view's), into `decisions`.
ConditionView decide_condition_view(const Protocol& P, const ScanCondition& condition, const std::vector<Stage>& stages,
                                    size_t v, size_t n_views, StageDecision* decisions) {
  const EvalParams& params = P.params;
  const EvalResult& r = P.r;
  const MethodId method = r.change_method;
  const size_t o = static_cast<size_t>(P.views[v].object);
  const int fold = r.object_fold[o];
  const Cloud raw = condition_view(P.objects[o].mesh, P.objects[o].any_pose, P.full[o], size_t(P.views[v].view), n_views, P.object_seed(o),
                                   condition, params.points_per_object, params.hpr_radius_factor);
  ScanFilterParams fp = params.filters;
  fp.relative_density = r.trained_density[size_t(fold)];
  ScanFilterReport report;
  const Cloud cloud = filter_scan(raw, fp, &report);
  const ConditionView seen{raw.points.size(), cloud.points.size(), report.ground > 0};
  const size_t ideal = std::max<size_t>(1, P.views[v].ideal_points ? P.views[v].ideal_points : P.views[v].cloud.points.size());
  const double full_equivalent = double(P.full[o].size()) * double(cloud.points.size()) / double(ideal);
  const Model& model = *P.fold_models[size_t(fold)];
  const ModelImpl& impl = *model.impl;
  for (size_t s = 0; s < stages.size(); ++s) {
    StageDecision& d = decisions[s];
    d.fold = fold, d.object = int(o), d.view = P.views[v].view, d.stage = stage_name(stages[s]), d.method = method;
    d.truth = r.object_truth[o];
    d.unknown_class = r.object_unknown_class[o];
    size_t count = cloud.points.size();
    if (stages[s].kind == StageKind::kFraction)
      count = std::min(count, size_t(std::llround(stages[s].value * full_equivalent)));
    d.points = count;
    if (count == 0) continue;
    auto f = cloud_features(reveal_top_down(cloud, count), P.features, P.base, 1);
    if (!f.ok()) continue;
    const MethodDecision decision = method_decision(impl, method, *f);
    const Eigen::VectorXd& scores = decision.scores;
    d.keypoints = f->positions.size();
    d.scores.assign(r.categories.size(), 0.0);
    const std::vector<int>& to_ours = P.fold_to_ours[size_t(fold)];
    for (int c = 0; c < int(scores.size()); ++c) d.scores[size_t(to_ours[size_t(c)])] = scores[c];
    Classification c;
    c.method = method;
    c.winner = argmax(scores);
    judge_unknown(model, decision, *f, c);  // the model's own operating point, as Classify answers
    d.winner = to_ours[size_t(c.winner)];
    d.novelty = c.novelty, d.unknown = c.unknown;
  }
  return seen;
}

double median_of(std::vector<size_t> x) {
  if (x.empty()) return 0.0;
  std::nth_element(x.begin(), x.begin() + std::ptrdiff_t(x.size() / 2), x.end());
  return double(x[x.size() / 2]);
}

// The matrix's row of a condition: closest and right-and-accepted accuracy per main stage (none for
// keypoint stages), unknown views accepted, views whose first stage failed, views with a ground plane
// removed, median points before and after the filters.
RobustnessRow robustness_row(const EvalResult& r, const ScanCondition& condition, size_t n_stages,
                             const std::vector<StageDecision>& decisions, const std::vector<ConditionView>& seen) {
  const MethodId method = r.change_method;
  RobustnessRow row;
  row.condition = condition;
  row.views = seen.size();
  std::vector<StageDecision> accepted = decisions;  // "unknown" counts as no decision
  for (StageDecision& d : accepted)
    if (d.unknown) d.winner = -1;
  for (const Stage& s : r.params.stages) {
    if (s.kind == StageKind::kKeypoints) {
      row.accuracy.push_back(NAN), row.accepted.push_back(NAN), row.balanced.push_back(NAN);
      continue;
    }
    row.accuracy.push_back(accuracy(decisions, stage_name(s), method).percent());
    row.accepted.push_back(accuracy(accepted, stage_name(s), method).percent());
    row.balanced.push_back(balanced_accuracy(decisions, stage_name(s), method, r.categories.size()));
  }
  std::vector<size_t> raw_points, kept_points;
  size_t unknown_views = 0, unknown_accepted = 0;
  for (size_t i = 0; i < seen.size(); ++i) {
    const StageDecision& full = decisions[i * n_stages];
    row.failed += full.winner < 0;
    row.ground_views += seen[i].ground;
    raw_points.push_back(seen[i].raw_points), kept_points.push_back(seen[i].kept_points);
    if (full.truth < 0) {
      ++unknown_views, unknown_accepted += accepted[i * n_stages].winner >= 0;
      continue;
    }
    row.full_views.push_back({seen[i].kept_points, full.winner == full.truth, accepted[i * n_stages].winner == full.truth});
  }
  if (unknown_views) row.unknown_accepted = 100.0 * double(unknown_accepted) / double(unknown_views);
  row.median_points_raw = median_of(raw_points);
  row.median_points = median_of(kept_points);
  return row;
}

}  // namespace

void robustness_matrix(Protocol& P) {
  const EvalParams& params = P.params;
  if (params.matrix.empty() || P.fold_models.empty()) return;
  EvalResult& r = P.r;
  const size_t n_views = std::clamp<size_t>(params.views_per_object, 1, 6);
  const size_t k = std::clamp<size_t>(params.matrix_views_per_object, 1, n_views);
  std::vector<size_t> chosen;  // k of each tested object's views, evenly spaced
  for (size_t v = 0; v < P.views.size(); ++v)
    if (P.tested(v) && (size_t(P.views[v].view) * k) % n_views < k) chosen.push_back(v);
  std::vector<Stage> stages;
  for (const Stage& s : params.stages)
    if (s.kind != StageKind::kKeypoints) stages.push_back(s);  // keypoint cuts need the full view's keypoints

  for (const ScanCondition& condition : params.matrix) {
    const auto t0 = Clock::now();
    std::vector<StageDecision> decisions(chosen.size() * stages.size());
    std::vector<ConditionView> seen(chosen.size());
    parallel_for(chosen.size(), P.threads, "robustness: " + describe(condition), P.progress, [&](size_t i) {
      seen[i] = decide_condition_view(P, condition, stages, chosen[i], n_views, decisions.data() + i * stages.size());
    });
    RobustnessRow row = robustness_row(r, condition, stages.size(), decisions, seen);
    row.seconds = seconds_since(t0);
    r.robustness.push_back(std::move(row));
  }
  double total = 0;
  for (const RobustnessRow& row : r.robustness) total += row.seconds;
  r.timings.push_back({"robustness matrix", total,
                       std::to_string(params.matrix.size()) + " conditions x " + std::to_string(chosen.size()) + " views"});
}

}  // namespace eval_internal
}  // namespace glimpse
