// Views as real sensors take them, under the conditions the robustness matrix and the training recipe name.
#include "glimpse/views/scan_conditions.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "glimpse/random.h"
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

bool distance_drawn(const ScanCondition& c) { return c.distance_to_m > c.distance_m; }
bool elevation_drawn(const ScanCondition& c) { return c.elevation_to_deg > c.elevation_deg; }

// "2", or "0.8-4" for a range.
std::string span(float from, float to, bool drawn) {
  std::string s = number(from);
  if (drawn) s.append("-").append(number(to));
  return s;
}

// The sensor's pose for view `view` of an object whose bounding box is `b`: its condition's distance and
// elevation, drawn in their ranges, the elevation raised until the sensor is not below the ground.
SensorPose condition_pose(const Bounds& b, size_t viewpoint, const ScanCondition& c, uint64_t view_seed) {
  float distance = c.distance_m, elevation = c.elevation_deg;
  if (distance_drawn(c)) distance += float(uniform01(splitmix64(view_seed, 11))) * (c.distance_to_m - c.distance_m);
  if (elevation_drawn(c))
    elevation += float(uniform01(splitmix64(view_seed, 12))) * (c.elevation_to_deg - c.elevation_deg);
  const float centre_z = b.centre().z();
  if (elevation < 0 && centre_z + distance * std::sin(elevation * float(M_PI) / 180.f) < 0)
    elevation = -std::asin(std::min(1.f, centre_z / distance)) * 180.f / float(M_PI);
  return orbit_pose(b.centre(), 60.f * float(viewpoint), elevation, distance);
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
    s.append(" ").append(span(c.distance_m, c.distance_to_m, distance_drawn(c))).append(" m, ");
    s.append(span(c.elevation_deg, c.elevation_to_deg, elevation_drawn(c))).append(" deg");
  }
  if (c.tilt_deg > 0) s += ", up off by <= " + number(c.tilt_deg) + " deg";
  if (c.floor) s += ", floor";
  if (c.outliers > 0) s += ", " + number(100 * c.outliers) + " % outliers";
  return s;
}

std::string describe(const std::vector<ScanCondition>& conditions) {
  std::string out;
  for (size_t i = 0; i < conditions.size(); ++i) {
    if (conditions[i].draw > 0) continue;  // counted with its first draw
    size_t draws = 1;
    for (size_t j = i + 1; j < conditions.size(); ++j) {
      ScanCondition again = conditions[j];
      again.draw = 0;
      draws += again == conditions[i];
    }
    out.append(out.empty() ? "" : "; ").append(describe(conditions[i]));
    if (draws > 1) out.append(" (").append(std::to_string(draws)).append(" draws)");
  }
  return out;
}

Cloud condition_view(const Mesh& mesh, bool any_pose, const Points& full, size_t view, size_t views, uint64_t seed,
                     const ScanCondition& c, size_t points_per_object, double hpr_radius_factor) {
  views = std::clamp<size_t>(views, 1, 6);
  std::string key = "condition " + describe(c) + " view " + std::to_string(view);
  if (c.draw > 0) key.append(" draw ").append(std::to_string(c.draw));
  const uint64_t view_seed = object_seed(seed, key);
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
    const SensorPose pose = condition_pose(b, viewpoint, c, view_seed);
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

namespace {

// "2" or "0.8-4" (a range, its ends in order) within [lo, hi]; false if it is neither.
bool parse_span(const std::string& text, double lo, double hi, float& from, float& to) {
  if (text.empty()) return false;
  char* end = nullptr;
  const double a = std::strtod(text.c_str(), &end);
  double b = a;
  if (*end == '-' && end != text.c_str()) {
    const char* rest = end + 1;
    if (!*rest) return false;
    b = std::strtod(rest, &end);
    if (end == rest || !(b > a)) return false;
  }
  if (*end || !(a >= lo && a <= hi && b >= lo && b <= hi)) return false;
  from = float(a), to = float(b);
  return true;
}

}  // namespace

Expected<std::vector<ScanCondition>> parse_training_sensors(std::string_view text) {
  std::vector<ScanCondition> out;
  if (text == "none") return out;
  std::string list(text);
  std::stringstream items(list);
  for (std::string item; std::getline(items, item, ',');) {
    const std::string usage = "training sensors are SENSOR:METRES:DEGREES items (e.g. depth:2:30, lidar32:10:5, "
                              "depth:0.8-4:-10-60) or 'none', not '" + item + "'";
    const size_t a = item.find(':'), b = a == std::string::npos ? a : item.find(':', a + 1);
    if (b == std::string::npos) return invalid_argument(usage);
    auto sensor = parse_sensor(item.substr(0, a));
    if (!sensor.ok() || sensor->sensor == SensorKind::kIdeal)
      return invalid_argument(usage + ": the sensor is depth, lidar, lidar32 or lidar64");
    ScanCondition c = *sensor;
    float d_to = 0, e_to = 0;
    if (!parse_span(item.substr(a + 1, b - a - 1), 1e-3, 100, c.distance_m, d_to) || !(c.distance_m > 0))
      return invalid_argument(usage + ": metres in (0, 100], or a range of them such as 0.8-4");
    if (!parse_span(item.substr(b + 1), -90, 90, c.elevation_deg, e_to))
      return invalid_argument(usage + ": degrees in [-90, 90], or a range of them such as -10-60");
    if (d_to > c.distance_m) c.distance_to_m = d_to;
    if (e_to > c.elevation_deg) c.elevation_to_deg = e_to;
    for (const ScanCondition& before : out) {
      ScanCondition same = before;
      same.draw = c.draw;
      c.draw += same == c;
    }
    out.push_back(c);
  }
  if (out.empty()) return invalid_argument("no training sensor given (e.g. depth:2:30, or 'none')");
  return out;
}

std::string training_sensors_spec(const std::vector<ScanCondition>& sensors) {
  std::string out;
  for (const ScanCondition& c : sensors) {
    out.append(out.empty() ? "" : ",").append(sensor_spec_name(c)).append(":");
    out.append(span(c.distance_m, c.distance_to_m, distance_drawn(c))).append(":");
    out.append(span(c.elevation_deg, c.elevation_to_deg, elevation_drawn(c)));
  }
  return out.empty() ? "none" : out;
}

}  // namespace glimpse
