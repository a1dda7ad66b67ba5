// Test views as real sensors take them (sensors.h) and the robustness matrix: the trained fold models
// classify each tested object's views under each scan condition, after the same filters.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "evaluation_format.h"
#include "evaluation_internal.h"
#include "glimpse/views.h"

namespace glimpse {

std::string_view sensor_name(SensorKind kind) {
  switch (kind) {
    case SensorKind::kIdeal: return "ideal";
    case SensorKind::kDepthCamera: return "depth";
    case SensorKind::kLidar: return "lidar";
  }
  return "?";
}

Expected<SensorKind> parse_sensor(std::string_view name) {
  for (SensorKind k : {SensorKind::kIdeal, SensorKind::kDepthCamera, SensorKind::kLidar})
    if (name == sensor_name(k)) return k;
  return invalid_argument("unknown sensor '" + std::string(name) + "' (valid: ideal, depth, lidar)");
}

Expected<std::vector<ScanCondition>> parse_training_sensors(std::string_view text) {
  std::vector<ScanCondition> out;
  if (text == "none") return out;
  std::string list(text);
  std::stringstream items(list);
  for (std::string item; std::getline(items, item, ',');) {
    const std::string usage = "training sensors are SENSOR:METRES:DEGREES items (e.g. depth:2:30) or 'none', not '" + item + "'";
    const size_t a = item.find(':'), b = a == std::string::npos ? a : item.find(':', a + 1);
    if (b == std::string::npos) return invalid_argument(usage);
    auto sensor = parse_sensor(item.substr(0, a));
    if (!sensor.ok() || *sensor == SensorKind::kIdeal) return invalid_argument(usage + ": the sensor is depth or lidar");
    char* end = nullptr;
    const std::string ds = item.substr(a + 1, b - a - 1), es = item.substr(b + 1);
    const double d = std::strtod(ds.c_str(), &end);
    if (ds.empty() || *end || !(d > 0 && d <= 100)) return invalid_argument(usage + ": metres in (0, 100]");
    const double e = std::strtod(es.c_str(), &end);
    if (es.empty() || *end || !(e >= -90 && e <= 90)) return invalid_argument(usage + ": degrees in [-90, 90]");
    ScanCondition c;
    c.sensor = *sensor, c.distance_m = float(d), c.elevation_deg = float(e);
    out.push_back(c);
  }
  if (out.empty()) return invalid_argument("no training sensor given (e.g. depth:2:30, or 'none')");
  return out;
}

namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

std::string training_sensors_spec(const std::vector<ScanCondition>& sensors) {
  std::string out;
  for (const ScanCondition& c : sensors)
    out += (out.empty() ? "" : ",") + std::string(sensor_name(c.sensor)) + ":" + number(c.distance_m) + ":" + number(c.elevation_deg);
  return out.empty() ? "none" : out;
}

std::string describe(const ScanCondition& c) {
  if (!c.label.empty()) return c.label;
  std::string s;
  switch (c.sensor) {
    case SensorKind::kIdeal: s = "ideal"; break;
    case SensorKind::kDepthCamera: s = "depth camera"; break;
    case SensorKind::kLidar: s = "LiDAR 16 beams"; break;
  }
  if (c.sensor == SensorKind::kIdeal) {
    if (c.density != 1) s += ", density " + number(c.density) + "x";
  } else {
    s += " " + number(c.distance_m) + " m, " + number(c.elevation_deg) + " deg";
  }
  if (c.tilt_deg > 0) s += ", up off by <= " + number(c.tilt_deg) + " deg";
  if (c.floor) s += ", floor";
  if (c.outliers > 0) s += ", " + number(100 * c.outliers) + " % outliers";
  return s;
}

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

Cloud condition_view(const EvalObject& object, const Points& full, size_t view, size_t views, uint64_t seed,
                     const ScanCondition& c, size_t points_per_object, double hpr_radius_factor) {
  views = std::clamp<size_t>(views, 1, 6);
  const uint64_t view_seed = object_seed(seed, "condition " + describe(c) + " view " + std::to_string(view));
  Cloud cloud;
  if (c.sensor == SensorKind::kIdeal) {
    if (c.density == 1 || points_per_object == 0) {
      cloud = object_view(full, view, views, object.any_pose, seed, hpr_radius_factor);
    } else {
      const size_t n = std::max<size_t>(100, size_t(std::llround(c.density * double(points_per_object))));
      cloud = object_view(object_cloud(object.mesh, n, seed), view, views, object.any_pose, seed, hpr_radius_factor);
    }
  } else {
    Mesh posed = object.mesh;
    if (object.any_pose) {  // the pose object_view gives this view
      posed.vertices = rotate_points(posed.vertices, random_rotation(object_seed(seed, std::to_string(view))));
      posed = place_on_ground(std::move(posed));
    }
    const Bounds b = bounds(posed.vertices);
    const float floor_half = c.floor ? 0.5f * std::max(b.extent().x(), b.extent().y()) + 0.5f : 0.f;
    auto scene = RayScene::build(posed, floor_half);
    if (!scene.ok()) return Cloud{};
    const size_t viewpoint = (std::min(view, views - 1) * 6) / views;  // the ideal view's azimuth
    const SensorPose pose = orbit_pose(b.centre(), 60.f * float(viewpoint), c.elevation_deg, c.distance_m);
    cloud = c.sensor == SensorKind::kDepthCamera ? depth_camera_scan(*scene, pose, DepthCameraParams{}, view_seed)
                                                 : lidar_scan(*scene, pose, LidarParams{}, view_seed);
  }
  if (c.outliers > 0) cloud = add_outliers(cloud, c.outliers, view_seed + 1);
  if (c.tilt_deg > 0) cloud = rotate_about_centroid(cloud, random_tilt(view_seed + 2, c.tilt_deg));
  return cloud;
}

double median_density(std::vector<double> densities) {
  std::erase_if(densities, [](double x) { return !(x > 0); });
  if (densities.empty()) return 0.0;
  std::nth_element(densities.begin(), densities.begin() + std::ptrdiff_t(densities.size() / 2), densities.end());
  return densities[densities.size() / 2];
}

double median_relative_density(const std::vector<Cloud>& views) {
  std::vector<double> d;
  for (const Cloud& c : views) d.push_back(relative_density(c.points));
  return median_density(std::move(d));
}

Cloud sensor_training_view(const EvalObject& object, const Points& full, size_t view, size_t views, uint64_t seed,
                           const ScanCondition& condition, size_t points_per_object, double hpr_radius_factor,
                           double trained_density, ScanFilterParams filters) {
  filters.relative_density = trained_density;
  Cloud cloud = filter_scan(condition_view(object, full, view, views, seed, condition, points_per_object, hpr_radius_factor),
                            filters);
  // A camera that sees a sliver of the object (too close, or past its far end) teaches nothing, and
  // training refuses a whole cloud without features: such a view is left out (empty).
  if (cloud.points.size() < 2 * FeatureParams{}.min_points) return Cloud{};
  return cloud;
}

std::vector<ScanCondition> default_training_sensors() {
  ScanCondition near, far;
  near.sensor = far.sensor = SensorKind::kDepthCamera;
  near.distance_m = 1.5f, near.elevation_deg = 15.f;
  far.distance_m = 3.f, far.elevation_deg = 45.f;
  return {near, far};
}

namespace eval_internal {

void robustness_matrix(Protocol& P) {
  const EvalParams& params = P.params;
  if (params.matrix.empty() || P.fold_models.empty()) return;
  EvalResult& r = P.r;
  const MethodId method = r.change_method;
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
    std::vector<size_t> raw_points(chosen.size()), kept_points(chosen.size()), ground(chosen.size());
    parallel_for(chosen.size(), P.threads, "robustness: " + describe(condition), P.progress, [&](size_t i) {
      const size_t v = chosen[i];
      const size_t o = static_cast<size_t>(P.views[v].object);
      const int fold = r.object_fold[o];
      const Cloud raw = condition_view(P.objects[o], P.full[o], size_t(P.views[v].view), n_views, P.object_seed(o),
                                       condition, params.points_per_object, params.hpr_radius_factor);
      ScanFilterParams fp = params.filters;
      fp.relative_density = r.trained_density[size_t(fold)];
      ScanFilterReport report;
      const Cloud cloud = filter_scan(raw, fp, &report);
      raw_points[i] = raw.points.size(), kept_points[i] = cloud.points.size(), ground[i] = report.ground > 0;
      // The stage cuts: the same share of this view's points as of the ideal view's.
      const size_t ideal = std::max<size_t>(1, P.views[v].ideal_points ? P.views[v].ideal_points : P.views[v].cloud.points.size());
      const double full_equivalent = double(P.full[o].size()) * double(cloud.points.size()) / double(ideal);
      const ModelImpl& impl = *P.fold_models[size_t(fold)]->impl;
      for (size_t s = 0; s < stages.size(); ++s) {
        StageDecision& d = decisions[i * stages.size() + s];
        d.fold = fold, d.object = int(o), d.view = P.views[v].view, d.stage = stage_name(stages[s]), d.method = method;
        d.truth = r.object_truth[o];
        size_t count = cloud.points.size();
        if (stages[s].kind == StageKind::kFraction)
          count = std::min(count, size_t(std::llround(stages[s].value * full_equivalent)));
        d.points = count;
        if (count == 0) continue;
        auto f = cloud_features(reveal_top_down(cloud, count), P.tp, P.base, 1);
        if (!f.ok()) continue;
        const Eigen::VectorXd scores = method_scores(impl, method, *f);
        d.keypoints = f->positions.size();
        d.scores.assign(r.categories.size(), 0.0);
        const std::vector<int>& to_ours = P.fold_to_ours[size_t(fold)];
        for (int c = 0; c < int(scores.size()); ++c) d.scores[size_t(to_ours[size_t(c)])] = scores[c];
        d.winner = to_ours[size_t(argmax(scores))];
      }
    });
    RobustnessRow row;
    row.condition = condition;
    row.views = chosen.size();
    for (const Stage& s : params.stages) {
      if (s.kind == StageKind::kKeypoints) {
        row.accuracy.push_back(NAN), row.balanced.push_back(NAN);
        continue;
      }
      row.accuracy.push_back(accuracy(decisions, stage_name(s), method).percent());
      row.balanced.push_back(balanced_accuracy(decisions, stage_name(s), method, r.categories.size()));
    }
    for (size_t i = 0; i < chosen.size(); ++i) {
      row.failed += decisions[i * stages.size()].winner < 0;
      row.ground_views += ground[i];
    }
    auto median = [](std::vector<size_t> x) {
      if (x.empty()) return 0.0;
      std::nth_element(x.begin(), x.begin() + std::ptrdiff_t(x.size() / 2), x.end());
      return double(x[x.size() / 2]);
    };
    row.median_points_raw = median(raw_points);
    row.median_points = median(kept_points);
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
