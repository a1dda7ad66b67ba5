// Test views as real sensors take them (views/sensors.h) and the robustness matrix: the trained fold models
// classify each tested object's views under each scan condition, after the same filters.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "report_format.h"
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
  auto sensor = [](SensorKind k, float d, float e) {
    ScanCondition c;
    c.sensor = k, c.distance_m = d, c.elevation_deg = e;
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
  const ModelImpl& impl = *P.fold_models[size_t(fold)]->impl;
  for (size_t s = 0; s < stages.size(); ++s) {
    StageDecision& d = decisions[s];
    d.fold = fold, d.object = int(o), d.view = P.views[v].view, d.stage = stage_name(stages[s]), d.method = method;
    d.truth = r.object_truth[o];
    size_t count = cloud.points.size();
    if (stages[s].kind == StageKind::kFraction)
      count = std::min(count, size_t(std::llround(stages[s].value * full_equivalent)));
    d.points = count;
    if (count == 0) continue;
    auto f = cloud_features(reveal_top_down(cloud, count), P.features, P.base, 1);
    if (!f.ok()) continue;
    const Eigen::VectorXd scores = method_scores(impl, method, *f);
    d.keypoints = f->positions.size();
    d.scores.assign(r.categories.size(), 0.0);
    const std::vector<int>& to_ours = P.fold_to_ours[size_t(fold)];
    for (int c = 0; c < int(scores.size()); ++c) d.scores[size_t(to_ours[size_t(c)])] = scores[c];
    d.winner = to_ours[size_t(argmax(scores))];
  }
  return seen;
}

double median_of(std::vector<size_t> x) {
  if (x.empty()) return 0.0;
  std::nth_element(x.begin(), x.begin() + std::ptrdiff_t(x.size() / 2), x.end());
  return double(x[x.size() / 2]);
}

// The matrix's row of a condition: accuracy per main stage (none for keypoint stages), views whose first
// stage failed, views with a ground plane removed, median points before and after the filters.
RobustnessRow robustness_row(const EvalResult& r, const ScanCondition& condition, size_t n_stages,
                             const std::vector<StageDecision>& decisions, const std::vector<ConditionView>& seen) {
  const MethodId method = r.change_method;
  RobustnessRow row;
  row.condition = condition;
  row.views = seen.size();
  for (const Stage& s : r.params.stages) {
    if (s.kind == StageKind::kKeypoints) {
      row.accuracy.push_back(NAN), row.balanced.push_back(NAN);
      continue;
    }
    row.accuracy.push_back(accuracy(decisions, stage_name(s), method).percent());
    row.balanced.push_back(balanced_accuracy(decisions, stage_name(s), method, r.categories.size()));
  }
  std::vector<size_t> raw_points, kept_points;
  for (size_t i = 0; i < seen.size(); ++i) {
    row.failed += decisions[i * n_stages].winner < 0;
    row.ground_views += seen[i].ground;
    raw_points.push_back(seen[i].raw_points), kept_points.push_back(seen[i].kept_points);
  }
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

namespace glimpse::eval_internal {

std::string robustness_section(const EvalResult& r) {
  std::string o;
  const ScanCondition& test = r.params.test_condition;
  if (!test.is_ideal())
    o += "## Test views from a simulated sensor\n\nEvery tested view above was taken as **" + describe(test) +
         "** (rays cast against the mesh, Embree), then filtered (ground plane, isolated points, voxel grid to the "
         "training views' density); training views are the ideal ones. Stage fractions are the same share of the "
         "sensor view's points as of the ideal view's.\n\n";
  if (r.robustness.empty()) return o;
  std::vector<std::string> stages;
  for (const Stage& s : r.params.stages)
    if (s.kind != StageKind::kKeypoints) stages.push_back(stage_name(s));
  o += "## Robustness matrix: real sensors and scene residue\n\n";
  o += "The models above (" + std::string(method_name(r.change_method)) +
       ", trained on ideal views) classify " + std::to_string(r.robustness.front().views) +
       " tested views (" + std::to_string(r.params.matrix_views_per_object) +
       " per object) taken under each condition, after the filters every scan goes through: RANSAC ground plane, "
       "isolated points, voxel grid down to the training views' density (median relative density ";
  for (size_t i = 0; i < r.trained_density.size(); ++i) o += (i ? ", " : "") + pct(r.trained_density[i], 1);
  o += " points per extent^2). Depth camera: 640x480, 57x43 deg, 0.5-4.5 m, sigma(z) = 1.2 mm + 1.9 mm (z - 0.4)^2, "
       "1/8 px disparity steps, returns thinning beyond 70 deg incidence; it aims at the object's centre, so a large "
       "object near it is cut by the field of view. LiDAR: 16 beams over +-15 deg, 0.2 deg steps, 1.5 cm range noise. "
       "Delta: points against the first (ideal) row.\n\n| condition | points raw | points kept | ground removed |";
  for (const std::string& s : stages) o += " " + s + " |";
  for (const std::string& s : stages) o += " delta " + s + " |";
  o += " balanced " + stages.front() + " | no decision | seconds |\n|---|---:|---:|---:|";
  for (size_t i = 0; i < 2 * stages.size() + 3; ++i) o += "---:|";
  o += "\n";
  const RobustnessRow& base = r.robustness.front();
  auto main_values = [&](const std::vector<double>& v) {
    std::vector<double> out;
    for (size_t s = 0; s < r.params.stages.size() && s < v.size(); ++s)
      if (r.params.stages[s].kind != StageKind::kKeypoints) out.push_back(v[s]);
    return out;
  };
  const std::vector<double> base_acc = main_values(base.accuracy);
  for (const RobustnessRow& row : r.robustness) {
    const std::vector<double> acc = main_values(row.accuracy), bal = main_values(row.balanced);
    o += "| " + describe(row.condition) + " | " + std::to_string(std::llround(row.median_points_raw)) + " | " +
         std::to_string(std::llround(row.median_points)) + " | " + std::to_string(row.ground_views) + " |";
    for (double a : acc) o += " " + pct(a, 1) + " |";
    for (size_t s = 0; s < acc.size(); ++s) {
      const double d = acc[s] - base_acc[s];
      o += " " + (&row == &base ? std::string("–") : (d >= 0 ? "+" : "") + pct(d, 1)) + " |";
    }
    o += " " + pct(bal.empty() ? NAN : bal.front(), 1) + " | " + std::to_string(row.failed) + " | " + pct(row.seconds, 1) + " |\n";
  }
  o += "\nPoints are medians per view (full view). \"no decision\": full views left with too few points to decide "
       "(counted as wrong).\n\n";
  return o;
}

}  // namespace glimpse::eval_internal
