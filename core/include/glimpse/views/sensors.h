// Simulated range sensors: single views as a depth camera or a spinning LiDAR would return them, by
// casting rays against the mesh (Intel Embree), so density follows distance and incidence as in a real
// scan, with each sensor's noise. The ideal views of sec. 3.4 (HPR on uniform samples) are hidden_point_removal.h's.
// World convention as in placement.h: metres, +z up, the object on the ground (z = 0).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

// ---- the scene rays are cast against ----

// A mesh in a ray-casting acceleration structure (Embree BVH), optionally with a square floor patch at
// z = 0 centred under it. Immutable once built; cast() may be called from any number of threads.
class RayScene {
 public:
  struct Hit {
    bool hit = false;
    float distance = 0;           // along the (unit) ray, metres
    Vec3 normal = Vec3::Zero();   // unit geometric normal, facing the ray's origin
    bool floor = false;           // the floor patch, not the object
  };

  // `floor_half_size_m` > 0 adds the floor patch [-h, h]^2 x {0} (shifted under the mesh's
  // bounding-box centre). An empty mesh or a non-finite vertex is an error.
  static Expected<RayScene> build(const Mesh& mesh, float floor_half_size_m = 0);

  // The first surface along origin + t dir, t in (0, max_distance]; `dir` need not be unit.
  Hit cast(const Vec3& origin, const Vec3& dir, float max_distance) const;
  // cast() for each of `dirs` (with its own max distance) from one origin, traced as packets of 8
  // neighbouring rays (a camera row's pixels) at about a third of the cost: the same hit at the same
  // distance, except that where two faces lie at exactly that distance (a ray through an edge, a
  // duplicated face) the packet may report the other one's normal. `max_distances` and `out` hold
  // one entry per direction.
  void cast_many(const Vec3& origin, std::span<const Vec3> dirs, std::span<const float> max_distances,
                 std::span<Hit> out) const;

  const Bounds& object_bounds() const { return bounds_; }
  // Everything a ray can hit: the object and the floor patch.
  const Bounds& scene_bounds() const { return scene_bounds_; }

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
  Bounds bounds_, scene_bounds_;
};

// ---- where the sensor is ----

struct SensorPose {
  Vec3 position = Vec3::Zero();
  Vec3 target = Vec3::Zero();  // what it looks at (a depth camera's optical axis passes through it)
};

// A sensor `distance_m` from `target`, `elevation_deg` above the horizon, `azimuth_deg` about +z.
SensorPose orbit_pose(const Vec3& target, float azimuth_deg, float elevation_deg, float distance_m);

// ---- a Kinect-class depth camera ----

struct DepthCameraParams {
  int width = 640, height = 480;       // pixels
  float fov_h_deg = 57.f, fov_v_deg = 43.f;
  float min_range_m = 0.5f, max_range_m = 4.5f;  // depth (along the optical axis) outside: no return
  // Axial noise after Nguyen, Izadi & Lovell 2012: sigma(z) = a + b (z - c)^2, z the depth.
  float noise_a_m = 0.0012f, noise_b_per_m = 0.0019f, noise_c_m = 0.4f;
  // Disparity quantisation of a structured-light camera: depth is focal x baseline / disparity with
  // disparity in steps of disparity_step_px (1/8 px on the Kinect); 0 = none.
  float baseline_m = 0.075f;
  float disparity_step_px = 0.125f;
  // Missing returns at grazing incidence: the angle between the ray and the surface normal; beyond
  // dropout_start_deg the return probability falls linearly to 0 at max_incidence_deg.
  float dropout_start_deg = 70.f, max_incidence_deg = 85.f;
  // Cast every pixel, not only the window onto the scene's bounds (the same points; bench_sensors' baseline).
  bool whole_frame = false;
};

// The camera at pose.position looking at pose.target, its image's up as close to +z as the axis
// allows; one ray per pixel centre. Points in world coordinates, sensor = the camera. Seeded. Only the
// pixels whose rays can reach the scene's bounds are cast (whole packets of 8): the same points as
// casting every pixel.
Cloud depth_camera_scan(const RayScene& scene, const SensorPose& pose, const DepthCameraParams& params,
                        uint64_t seed);

// ---- a spinning multi-beam LiDAR ----

struct LidarParams {
  int beams = 16;                              // Velodyne VLP-16 class
  float lowest_beam_deg = -15.f, highest_beam_deg = 15.f;  // elevation of the beams, evenly spaced
  float azimuth_step_deg = 0.2f;               // one full turn
  float min_range_m = 0.5f, max_range_m = 100.f;
  float range_noise_m = 0.015f;                // sigma, along the beam
  float max_incidence_deg = 87.f;              // no return beyond
};

// The LiDAR classes simulated, by beam count: 16 (VLP-16 class, -15..15 deg), 32 (VLP-32C class,
// -25..15 deg) and 64 (HDL-64E class, -24.9..2 deg, a vehicle's roof). Any other count is an error.
Expected<LidarParams> lidar_with_beams(int beams);

// The LiDAR at pose.position, spinning about +z (level; the target is not used). Seeded.
Cloud lidar_scan(const RayScene& scene, const SensorPose& pose, const LidarParams& params, uint64_t seed);

// ---- what a real scene leaves besides the object ----

// `fraction` x the cloud's size extra points, uniform in the cloud's bounding box grown by 10 % of its
// diagonal on every side (stray returns). Seeded; the sensor is kept.
Cloud add_outliers(const Cloud& cloud, double fraction, uint64_t seed);

}  // namespace glimpse
