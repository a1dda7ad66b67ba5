// Planes in a scan by RANSAC (PCL's SACSegmentation, inside the .cpp), and the up direction of a frame
// in the camera's own coordinates taken from the floor or table it sees: a depth camera's frame says
// nothing of which way is up, and the floor does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

// n . p + d = 0 with |n| = 1; `inliers` points lie within the fit's distance of it.
struct Plane {
  Vec3 normal = Vec3::UnitZ();
  float offset = 0;
  size_t inliers = 0;
};

struct PlaneFitParams {
  float distance_m = 0.02f;  // RANSAC inlier distance
  int max_iterations = 1000;
  // When set: only planes whose normal lies within max_angle_deg of this axis (either sign).
  std::optional<Vec3> axis;
  float max_angle_deg = 90.f;
};

// The plane holding the most of `points[subset]` by RANSAC (PCL's fixed seed: deterministic), its
// coefficients refined by least squares on its inliers; `inliers` (when given) receives their indices
// into `points`. None for fewer than 3 points or when no model is found. The points must be finite.
std::optional<Plane> fit_plane(const Points& points, const std::vector<uint32_t>& subset, const PlaneFitParams& params,
                               std::vector<uint32_t>* inliers = nullptr);

struct FloorParams {
  float distance_m = 0.02f;  // RANSAC inlier distance: a Kinect-class camera's noise at 2-3 m
  // A floor's normal, turned towards the sensor, lies within this of the image's up (the camera's
  // frame up, else -y: PCL's camera coordinates, y down): a camera looking down up to 75 degrees sees
  // it; a wall in front (90 degrees and more) or the ceiling does not qualify.
  float max_tilt_deg = 75.f;
  double min_fraction = 0.05;  // a floor holds at least this share of the cloud's finite points
  int max_planes = 4;          // planes tried, largest first, before giving up
  size_t max_points = 30000;   // RANSAC runs on an even subsample of at most this many points
};

// The up direction of a frame in the camera's own coordinates: the normal of the largest plane the
// camera looks down on (floor, table top), turned to the side the sensor is on (Cloud.sensor, else the
// origin). Non-finite points are skipped. Errors (kInvalidArgument): fewer than 3 finite points, or no
// such plane.
Expected<Vec3> floor_up(const Cloud& cloud, const FloorParams& params = {});

}  // namespace glimpse
