// The objects of a depth camera's frame: the large planes removed by RANSAC, largest first, and what
// remains split into clusters, one per object. A removed plane stays removed when it bounds the room
// (the floor, a wall: nothing lies behind it) or holds something (a table top with a cup on it); a bare
// table's top or a plane through an object's broad face (a person facing the camera) goes back to its
// object. Pieces of one object that a single view parts are joined: those that stand over one another,
// and those either side of a nearer object that hides what lies between them.
// PCL's SACSegmentation (through fit_plane) and kd-tree do the work inside the .cpp files.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/geometry/floor_plane.h"

namespace glimpse {

struct SceneParams {
  // Planes and clusters are found on the centroids of voxels this wide; each object then takes back
  // every frame point of its voxels. 0: on the frame's points themselves.
  float voxel_m = 0.01f;
  // A point within plane_distance_m + plane_distance_per_m2 x range^2 of a plane is on it (range: from
  // the sensor): a depth camera's noise and depth steps grow with the square of the range (Nguyen et al.
  // 2012; 1/8-pixel disparity steps are 2.5 cm at 3 m), so a floor 3.5 m away is as thick as 6 cm.
  float plane_distance_m = 0.02f;
  float plane_distance_per_m2 = 0.003f;
  double min_plane_fraction = 0.05;    // the smallest plane removed, as a share of the frame's voxels
  // A floor, wall or table top covers at least this much in one connected piece; a plane's smaller
  // pieces are objects' faces (a box's top, a laptop's screen) and stay for clustering.
  float min_plane_area_m2 = 0.25f;
  int max_planes = 8;                  // RANSAC fits at most, largest plane first
  size_t plane_fit_points = 1500;      // RANSAC scores an even subsample of at most this many voxels
  // Voxels closer than this belong to the same object: 3 cm bridges the gaps a depth camera leaves on one
  // object (a bottle's handle behind its shadow) and still parts objects 5 cm apart.
  float cluster_tolerance_m = 0.03f;
  // ... and farther out more: the depth camera's steps (1/8 pixel of disparity: 3.5 cm at 3.5 m) part one
  // surface into slabs. Two voxels join within max(cluster_tolerance_m, cluster_tolerance_per_m2 x
  // range^2): 3 cm to 2.6 m, 5.5 cm at 3.5 m.
  float cluster_tolerance_per_m2 = 0.0045f;
  // Frame points; fewer: noise, a plane's remnant or a piece of an object (a 20 cm object 4 m away still
  // has 1000). For a frame of a 640 x 480 depth camera; a sparser one asks for fewer (below).
  size_t min_object_points = 1000;
  // The frame density (frame_density, points per square degree) the counts and the cluster tolerance's
  // range term are set for: a real 640 x 480 Kinect's frames read about 84, the lab's camera about 110, a
  // 320 x 240 frame 21-30. A sparser frame scales min_object_points by its density over this (never below
  // 20) and the range term by the square root of the inverse (its depth steps widen with its pixels); the
  // 3 cm that parts objects stays. A denser frame keeps them. 0: everything as given, whatever the frame.
  double reference_density_per_deg2 = 80;
  size_t max_object_points = 200000;   // frame points; more: a wall or floor left over
  // The longest side of an object's box; longer: what is left of a wall or a floor. Room for a standing
  // person (2 m) and a conference table (3.5 m).
  float max_object_extent_m = 4.f;
  // A cluster with at least this share of its points within twice the inlier distance of the floor or a
  // wall is that plane's remnant (noise beyond the inlier distance, a strip seen between objects), not
  // an object.
  double max_remnant_share = 0.8;
  size_t max_objects = 32;             // the nearest ones are kept
};

struct SceneObject {
  std::vector<uint32_t> indices;  // into the frame's points, ascending
  Points points;                  // the frame's points at those indices
  Vec3 box_min = Vec3::Zero();    // axis-aligned box in the frame's coordinates
  Vec3 box_max = Vec3::Zero();
  Vec3 centroid = Vec3::Zero();
  float range_m = 0;              // the centroid's distance from the sensor (Cloud.sensor, else the origin)
};

struct Scene {
  // In the order removed (largest first); inliers count frame points; each normal faces the sensor
  // (Cloud.sensor, else the origin).
  std::vector<Plane> planes;
  std::vector<SceneObject> objects;  // nearest the sensor first; at equal range the larger first
  size_t finite_points = 0;          // the frame's points with a depth
  double density_per_deg2 = 0;       // the frame's points per square degree (frame_density)
  size_t min_object_points = 0;      // the fewest points an object had to have in this frame (at_density)
};

// Points per square degree seen from `sensor`: the median count over the occupied cells of two degrees on
// a plane facing the points' mean direction (where a camera's pixels lie evenly), so an object's edge
// cells, half empty, do not lower it. 0 without finite points ahead.
double frame_density(const Points& points, const Vec3& sensor);
// The parameters segment_scene uses on a frame of this density (SceneParams::reference_density_per_deg2).
SceneParams at_density(const SceneParams& params, double density_per_deg2);

// The planes and objects of `frame`. Non-finite points (an organised frame's missing depth) are skipped.
// Deterministic: the same frame gives the same scene. A frame without finite points gives an empty scene.
// Errors (kInvalidArgument): a negative voxel size, a non-positive plane distance or cluster tolerance,
// min_object_points above max_object_points.
Expected<Scene> segment_scene(const Cloud& frame, const SceneParams& params = {});

// How far from a plane a point at `p` may lie and still be on it, seen from `sensor`: the noise grows with
// the range (SceneParams::plane_distance_per_m2).
inline float plane_reach(const Vec3& p, const Vec3& sensor, const SceneParams& params) {
  return params.plane_distance_m + params.plane_distance_per_m2 * (p - sensor).squaredNorm();
}

// Whether a removed plane is a floor or a table top: level and below the sensor (its normal, which faces
// the sensor, within max_tilt_deg of +z). A frame with planes but no such one is probably not +z up (a
// camera's own coordinates, where a wall may pass for a ceiling).
inline bool has_level_plane(const Scene& scene, float max_tilt_deg = 20.f) {
  const float cos_max = std::cos(max_tilt_deg * std::numbers::pi_v<float> / 180.f);
  return std::any_of(scene.planes.begin(), scene.planes.end(),
                     [cos_max](const Plane& p) { return p.normal.z() >= cos_max; });
}

// One object as Classify takes it: its points with the frame's sensor and camera frame, so that an
// object at the image's edge is known to be cut there (Classification::frame_cut).
inline Cloud object_cloud(const Cloud& frame, const SceneObject& object) {
  return Cloud{object.points, frame.sensor, frame.frame};
}

}  // namespace glimpse
