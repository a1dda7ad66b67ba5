// Views as real sensors take them, under the conditions the robustness matrix and the training recipe name.
#include "glimpse/views/scan_conditions.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/sampling.h"
#include "glimpse/views/sensors.h"

namespace glimpse {

namespace {

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

std::string_view sensor_name(SensorKind kind) {
  switch (kind) {
    case SensorKind::kIdeal: return "ideal";
    case SensorKind::kDepthCamera: return "depth";
    case SensorKind::kLidar: return "lidar";
  }
  return "?";
}

Expected<ScanCondition> parse_sensor(std::string_view name) {
  ScanCondition c;
  for (SensorKind k : {SensorKind::kIdeal, SensorKind::kDepthCamera, SensorKind::kLidar})
    if (name == sensor_name(k)) return c.sensor = k, c;
  for (int beams : {16, 32, 64})
    if (name.starts_with("lidar") && name.substr(5) == std::to_string(beams))
      return c.sensor = SensorKind::kLidar, c.beams = beams, c;
  return invalid_argument("unknown sensor '" + std::string(name) + "' (valid: ideal, depth, lidar, lidar16, lidar32, lidar64)");
}

std::string sensor_spec_name(const ScanCondition& c) {
  if (c.sensor == SensorKind::kLidar && c.beams != 16) return std::string("lidar").append(std::to_string(c.beams));
  return std::string(sensor_name(c.sensor));
}

std::string describe(const ScanCondition& c) {
  if (!c.label.empty()) return c.label;
  std::string s;
  switch (c.sensor) {
    case SensorKind::kIdeal: s = "ideal"; break;
    case SensorKind::kDepthCamera: s = "depth camera"; break;
    case SensorKind::kLidar: s = std::string("LiDAR ").append(std::to_string(c.beams)).append(" beams"); break;
  }
  if (c.sensor == SensorKind::kIdeal) {
    if (c.density != 1) s += ", density " + number(c.density) + "x";
  } else {
    s.append(" ").append(number(c.distance_m)).append(" m, ").append(number(c.elevation_deg)).append(" deg");
  }
  if (c.tilt_deg > 0) s += ", up off by <= " + number(c.tilt_deg) + " deg";
  if (c.floor) s += ", floor";
  if (c.outliers > 0) s += ", " + number(100 * c.outliers) + " % outliers";
  return s;
}

Cloud condition_view(const Mesh& mesh, bool any_pose, const Points& full, size_t view, size_t views, uint64_t seed,
                     const ScanCondition& c, size_t points_per_object, double hpr_radius_factor) {
  views = std::clamp<size_t>(views, 1, 6);
  const uint64_t view_seed = object_seed(seed, "condition " + describe(c) + " view " + std::to_string(view));
  Cloud cloud;
  if (c.sensor == SensorKind::kIdeal) {
    if (c.density == 1 || points_per_object == 0) {
      cloud = object_view(full, view, views, any_pose, seed, hpr_radius_factor);
    } else {
      const size_t n = std::max<size_t>(100, size_t(std::llround(c.density * double(points_per_object))));
      cloud = object_view(object_cloud(mesh, n, seed), view, views, any_pose, seed, hpr_radius_factor);
    }
  } else {
    Mesh posed = mesh;
    if (any_pose) {  // the pose object_view gives this view
      posed.vertices = rotate_points(posed.vertices, random_rotation(object_seed(seed, std::to_string(view))));
      posed = place_on_ground(std::move(posed));
    }
    const Bounds b = bounds(posed.vertices);
    const float floor_half = c.floor ? 0.5f * std::max(b.extent().x(), b.extent().y()) + 0.5f : 0.f;
    auto scene = RayScene::build(posed, floor_half);
    if (!scene.ok()) return Cloud{};
    const size_t viewpoint = (std::min(view, views - 1) * 6) / views;  // the ideal view's azimuth
    const SensorPose pose = orbit_pose(b.centre(), 60.f * float(viewpoint), c.elevation_deg, c.distance_m);
    if (c.sensor == SensorKind::kDepthCamera) {
      cloud = depth_camera_scan(*scene, pose, DepthCameraParams{}, view_seed);
    } else if (auto lidar = lidar_with_beams(c.beams); lidar.ok()) {
      cloud = lidar_scan(*scene, pose, *lidar, view_seed);
    }
  }
  if (c.outliers > 0) cloud = add_outliers(cloud, c.outliers, view_seed + 1);
  if (c.tilt_deg > 0) cloud = rotate_about_centroid(cloud, random_tilt(view_seed + 2, c.tilt_deg));
  return cloud;
}

Expected<std::vector<ScanCondition>> parse_training_sensors(std::string_view text) {
  std::vector<ScanCondition> out;
  if (text == "none") return out;
  std::string list(text);
  std::stringstream items(list);
  for (std::string item; std::getline(items, item, ',');) {
    const std::string usage = "training sensors are SENSOR:METRES:DEGREES items (e.g. depth:2:30, lidar32:10:5) or 'none', not '" + item + "'";
    const size_t a = item.find(':'), b = a == std::string::npos ? a : item.find(':', a + 1);
    if (b == std::string::npos) return invalid_argument(usage);
    auto sensor = parse_sensor(item.substr(0, a));
    if (!sensor.ok() || sensor->sensor == SensorKind::kIdeal)
      return invalid_argument(usage + ": the sensor is depth, lidar, lidar32 or lidar64");
    char* end = nullptr;
    const std::string ds = item.substr(a + 1, b - a - 1), es = item.substr(b + 1);
    const double d = std::strtod(ds.c_str(), &end);
    if (ds.empty() || *end || !(d > 0 && d <= 100)) return invalid_argument(usage + ": metres in (0, 100]");
    const double e = std::strtod(es.c_str(), &end);
    if (es.empty() || *end || !(e >= -90 && e <= 90)) return invalid_argument(usage + ": degrees in [-90, 90]");
    ScanCondition c = *sensor;
    c.distance_m = float(d), c.elevation_deg = float(e);
    out.push_back(c);
  }
  if (out.empty()) return invalid_argument("no training sensor given (e.g. depth:2:30, or 'none')");
  return out;
}

std::string training_sensors_spec(const std::vector<ScanCondition>& sensors) {
  std::string out;
  for (const ScanCondition& c : sensors)
    out.append(out.empty() ? "" : ",").append(sensor_spec_name(c)).append(":").append(number(c.distance_m)).append(":").append(number(c.elevation_deg));
  return out.empty() ? "none" : out;
}

}  // namespace glimpse
