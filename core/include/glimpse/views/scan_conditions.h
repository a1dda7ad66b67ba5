// Views as real sensors take them: the paper's ideal views (sec. 3.4) or a simulated depth camera or LiDAR
// (sensors.h) in a scene, with a floor, stray points or a tilted up. The robustness matrix tests under
// these conditions and the training recipe learns from some of them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

enum class SensorKind : uint8_t {
  kIdeal,        // HPR on area-weighted samples from the paper's viewpoints (sec. 3.4)
  kDepthCamera,  // DepthCameraParams' Kinect-class camera, rays cast against the mesh
  kLidar,        // a spinning LiDAR of 16, 32 or 64 beams (lidar_with_beams)
};
std::string_view sensor_name(SensorKind kind);  // "ideal", "depth", "lidar"

struct ScanCondition {
  std::string label;  // the report's row name; empty: described from the fields
  SensorKind sensor = SensorKind::kIdeal;
  double density = 1;        // ideal: samples per object x this
  float distance_m = 2;      // depth / LiDAR: from the sensor to the object's bounding-box centre
  float elevation_deg = 30;  // depth / LiDAR: above the horizon, seen from that centre
  int beams = 16;            // LiDAR: 16, 32 or 64
  // A range of poses (training): each view draws its distance in [distance_m, distance_to_m] and its
  // elevation in [elevation_deg, elevation_to_deg] where these lie above them (seeded by the object, the
  // view and `draw`); otherwise the pose is fixed.
  float distance_to_m = 0, elevation_to_deg = -90;
  int draw = 0;  // the same range listed again: another draw of poses
  float tilt_deg = 0;        // the cloud's up off by up to this, in a random direction (seeded)
  bool floor = false;        // a floor patch under the object, seen by the sensor
  double outliers = 0;       // stray points, x the view's size
  bool operator==(const ScanCondition&) const = default;
  bool is_ideal() const { return *this == ScanCondition{label}; }
};
std::string describe(const ScanCondition& condition);  // "depth 2 m, 30 deg, floor, 2 % outliers"

// Several conditions, "; " between them, a range drawn again counted once: "depth camera 0.8-4 m,
// -10-60 deg (3 draws); LiDAR 16 beams 5-20 m, 5 deg".
std::string describe(const std::vector<ScanCondition>& conditions);

// A sensor by name, as a condition at the default pose: "ideal", "depth", "lidar" (16 beams), "lidar16",
// "lidar32" or "lidar64". The error lists the valid names.
Expected<ScanCondition> parse_sensor(std::string_view name);
// The name back: "ideal", "depth", "lidar" (16 beams), "lidar32", "lidar64".
std::string sensor_spec_name(const ScanCondition& condition);

// "depth:1.5:15,depth:3:45" (SENSOR:METRES:DEGREES, sensor depth, lidar, lidar32 or lidar64) or "none" (no
// sensor). METRES and DEGREES may be ranges, "0.8-4" and "-10-60": each view draws its pose in them; an
// item listed twice is a second draw. Errors name the bad item.
Expected<std::vector<ScanCondition>> parse_training_sensors(std::string_view text);
// The same text back: "depth:1.5:15,depth:3:45", "none" for no sensor.
std::string training_sensors_spec(const std::vector<ScanCondition>& sensors);

// One view of an object under a condition, as the sensor returns it (before any filter). Ideal views are
// object_view's; the others are cast against the object's mesh (upright, real-life size, on the ground)
// in the same pose (an object without a natural up, `any_pose`, gets the view's random pose), from the
// same azimuth as the ideal view, at the condition's distance and elevation (drawn in its ranges), never
// below the ground (a negative elevation rises until the sensor stands at z = 0). `full` is the object's
// full 3D cloud at the protocol's density (ideal views only), `object_seed` its seed (object_seed()).
Cloud condition_view(const Mesh& mesh, bool any_pose, const Points& full, size_t view, size_t views,
                     uint64_t object_seed, const ScanCondition& condition, size_t points_per_object,
                     double hpr_radius_factor);

}  // namespace glimpse
