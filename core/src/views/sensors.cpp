#include "glimpse/views/sensors.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <random>

#include "glimpse/random.h"

namespace glimpse {

namespace {

constexpr float kDeg = std::numbers::pi_v<float> / 180.f;

// One Embree device for the process, builds on the calling thread only ("threads=1"): the lab already
// runs one view per core, and a scene's rays give the same hits whatever built it.
RTCDevice shared_device() {
  static RTCDevice device = rtcNewDevice("threads=1");
  return device;
}

// Serialises the device's error channel (rtcGetDeviceError is per device, not per thread).
std::mutex& device_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

struct RayScene::Impl {
  RTCScene scene = nullptr;
  unsigned floor_id = RTC_INVALID_GEOMETRY_ID;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
  }
};

Expected<RayScene> RayScene::build(const Mesh& mesh, float floor_half_size_m) {
  if (mesh.vertices.empty() || mesh.faces.empty()) return invalid_argument("ray scene: the mesh has no triangles");
  for (const Vec3& v : mesh.vertices)
    if (!v.allFinite()) return invalid_argument("ray scene: the mesh has a non-finite vertex");
  const long n = static_cast<long>(mesh.vertices.size());
  for (const Eigen::Vector3i& f : mesh.faces)
    if ((f.array() < 0).any() || (f.array() >= n).any())
      return invalid_argument("ray scene: a face refers to a vertex that does not exist");
  RTCDevice device = shared_device();
  if (!device) return internal_error("ray scene: Embree could not create a device (rtcNewDevice failed)");

  std::lock_guard<std::mutex> lock(device_mutex());
  auto impl = std::make_shared<Impl>();
  impl->scene = rtcNewScene(device);
  rtcSetSceneFlags(impl->scene, RTC_SCENE_FLAG_ROBUST);
  auto add_triangles = [&](const Points& vertices, const std::vector<Eigen::Vector3i>& faces) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertices.size()));
    auto* ib = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), faces.size()));
    if (!vb || !ib) {
      rtcReleaseGeometry(g);
      return RTC_INVALID_GEOMETRY_ID;
    }
    for (size_t i = 0; i < vertices.size(); ++i)
      vb[3 * i] = vertices[i].x(), vb[3 * i + 1] = vertices[i].y(), vb[3 * i + 2] = vertices[i].z();
    for (size_t i = 0; i < faces.size(); ++i)
      for (int k = 0; k < 3; ++k) ib[3 * i + k] = static_cast<unsigned>(faces[i][k]);
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(impl->scene, g);
    rtcReleaseGeometry(g);
    return id;
  };
  if (add_triangles(mesh.vertices, mesh.faces) == RTC_INVALID_GEOMETRY_ID)
    return resource_exhausted("ray scene: Embree could not allocate the mesh's buffers");
  RayScene out;
  out.bounds_ = out.scene_bounds_ = bounds(mesh.vertices);
  if (floor_half_size_m > 0) {
    const Vec3 c = out.bounds_.centre();
    const float h = floor_half_size_m;
    const Points corners = {{c.x() - h, c.y() - h, 0.f}, {c.x() + h, c.y() - h, 0.f},
                            {c.x() + h, c.y() + h, 0.f}, {c.x() - h, c.y() + h, 0.f}};
    impl->floor_id = add_triangles(corners, {{0, 1, 2}, {0, 2, 3}});
    for (const Vec3& corner : corners)
      out.scene_bounds_.min = out.scene_bounds_.min.cwiseMin(corner), out.scene_bounds_.max = out.scene_bounds_.max.cwiseMax(corner);
    if (impl->floor_id == RTC_INVALID_GEOMETRY_ID)
      return resource_exhausted("ray scene: Embree could not allocate the floor's buffers");
  }
  rtcCommitScene(impl->scene);
  if (const RTCError e = rtcGetDeviceError(device); e != RTC_ERROR_NONE)
    return internal_error("ray scene: Embree failed to build the scene (error " + std::to_string(int(e)) + ")");
  out.impl_ = std::move(impl);
  return out;
}

namespace {

// A hit at `distance` along the unit ray `d`: the face's geometric normal made unit and turned to
// face the ray's origin.
RayScene::Hit found(const Vec3& d, float distance, Vec3 n, bool floor) {
  const float nn = n.norm();
  n = nn > 0 ? Vec3(n / nn) : Vec3(-d);
  if (n.dot(d) > 0) n = -n;
  return {true, distance, n, floor};
}

}  // namespace

RayScene::Hit RayScene::cast(const Vec3& origin, const Vec3& dir, float max_distance) const {
  Hit hit;
  const float len = dir.norm();
  if (!impl_ || !(len > 0) || !(max_distance > 0)) return hit;
  const Vec3 d = dir / len;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray.org_x = origin.x(), rh.ray.org_y = origin.y(), rh.ray.org_z = origin.z();
  rh.ray.dir_x = d.x(), rh.ray.dir_y = d.y(), rh.ray.dir_z = d.z();
  rh.ray.tnear = 0.f;
  rh.ray.tfar = max_distance;
  rh.ray.time = 0.f;
  rh.ray.mask = std::numeric_limits<unsigned>::max();
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  return found(d, rh.ray.tfar, Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z), rh.hit.geomID == impl_->floor_id);
}

void RayScene::cast_many(const Vec3& origin, std::span<const Vec3> dirs, std::span<const float> max_distances,
                         std::span<Hit> out) const {
  std::fill(out.begin(), out.end(), Hit{});
  if (!impl_) return;
  const size_t n = std::min({dirs.size(), max_distances.size(), out.size()});
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  for (size_t first = 0; first < n; first += 8) {
    alignas(32) RTCRayHit8 rh;
    alignas(32) int valid[8];
    Vec3 unit[8];
    for (size_t k = 0; k < 8; ++k) {
      const size_t i = first + k;
      const float len = i < n ? dirs[i].norm() : 0.f;
      valid[k] = i < n && len > 0 && max_distances[i] > 0 ? -1 : 0;
      unit[k] = valid[k] ? Vec3(dirs[i] / len) : Vec3::UnitX();
      rh.ray.org_x[k] = origin.x(), rh.ray.org_y[k] = origin.y(), rh.ray.org_z[k] = origin.z();
      rh.ray.dir_x[k] = unit[k].x(), rh.ray.dir_y[k] = unit[k].y(), rh.ray.dir_z[k] = unit[k].z();
      rh.ray.tnear[k] = 0.f;
      rh.ray.tfar[k] = valid[k] ? max_distances[i] : 0.f;
      rh.ray.time[k] = 0.f;
      rh.ray.mask[k] = std::numeric_limits<unsigned>::max();
      rh.ray.id[k] = static_cast<unsigned>(k);
      rh.ray.flags[k] = 0;
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect8(valid, impl_->scene, &context, &rh);
    for (size_t k = 0; k < 8 && first + k < n; ++k) {
      if (valid[k] && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID)
        out[first + k] = found(unit[k], rh.ray.tfar[k], Vec3(rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]),
                               rh.hit.geomID[k] == impl_->floor_id);
    }
  }
}

SensorPose orbit_pose(const Vec3& target, float azimuth_deg, float elevation_deg, float distance_m) {
  const float az = azimuth_deg * kDeg, el = elevation_deg * kDeg;
  const Vec3 dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  return {target + distance_m * dir, target};
}

namespace {

// Keeps a return with the probability the incidence angle leaves it (1 below `start`, 0 beyond `max`).
bool returns_at_incidence(float cos_incidence, float start_deg, float max_deg, std::mt19937_64& rng) {
  const float angle = std::acos(std::clamp(cos_incidence, 0.f, 1.f)) / kDeg;
  if (angle >= max_deg) return false;
  if (angle <= start_deg || max_deg <= start_deg) return true;
  return uniform01(rng) >= double((angle - start_deg) / (max_deg - start_deg));
}

// The pixels whose rays can reach `b`: the rectangle round the projections of its corners, a pixel
// wider on each side, its columns widened to whole packets of 8 (RayScene::cast_many casts a row in
// packets from column 0, so each packet holds the same rays as in a whole row). The whole frame when a
// corner lies behind the camera.
struct PixelWindow {
  int u0, u1, v0, v1;  // [u0, u1) x [v0, v1)
};
PixelWindow window_onto(const Bounds& b, const Vec3& position, const Vec3& forward, const Vec3& right, const Vec3& up,
                        float fx, float fy, int width, int height) {
  const PixelWindow whole{0, width, 0, height};
  float u_lo = INFINITY, u_hi = -INFINITY, v_lo = INFINITY, v_hi = -INFINITY;
  for (int i = 0; i < 8; ++i) {
    const Vec3 corner(i & 1 ? b.max.x() : b.min.x(), i & 2 ? b.max.y() : b.min.y(), i & 4 ? b.max.z() : b.min.z());
    const Vec3 d = corner - position;
    const float depth = d.dot(forward);
    if (!(depth > 1e-4f)) return whole;
    const float u = fx * d.dot(right) / depth + 0.5f * float(width) - 0.5f;
    const float v = 0.5f * float(height) - 0.5f - fy * d.dot(up) / depth;
    u_lo = std::min(u_lo, u), u_hi = std::max(u_hi, u), v_lo = std::min(v_lo, v), v_hi = std::max(v_hi, v);
  }
  if (!std::isfinite(u_lo + u_hi + v_lo + v_hi)) return whole;
  auto clamp_to = [](float x, int n) { return int(std::clamp(x, 0.f, float(n))); };
  PixelWindow w{clamp_to(std::floor(u_lo) - 1, width), clamp_to(std::ceil(u_hi) + 2, width),
                clamp_to(std::floor(v_lo) - 1, height), clamp_to(std::ceil(v_hi) + 2, height)};
  w.u0 -= w.u0 % 8;
  w.u1 = std::min(width, (w.u1 + 7) / 8 * 8);
  return w;
}

}  // namespace

Cloud depth_camera_scan(const RayScene& scene, const SensorPose& pose, const DepthCameraParams& p, uint64_t seed) {
  Cloud out;
  out.sensor = pose.position;
  const Vec3 axis = pose.target - pose.position;
  if (!(axis.norm() > 0) || p.width <= 0 || p.height <= 0) return out;
  const Vec3 forward = axis.normalized();
  Vec3 right = forward.cross(Vec3::UnitZ());
  if (right.norm() < 1e-6f) right = Vec3::UnitX();  // looking straight down or up
  right.normalize();
  const Vec3 up = right.cross(forward);
  out.frame = CameraFrame{forward, up, p.fov_h_deg, p.fov_v_deg};
  const float fx = 0.5f * float(p.width) / std::tan(0.5f * p.fov_h_deg * kDeg);
  const float fy = 0.5f * float(p.height) / std::tan(0.5f * p.fov_v_deg * kDeg);
  const double focal_baseline = double(fx) * p.baseline_m;  // disparity (px) x depth (m)
  std::mt19937_64 rng(seed);
  const PixelWindow w = p.whole_frame ? PixelWindow{0, p.width, 0, p.height}
                                      : window_onto(scene.scene_bounds(), pose.position, forward, right, up, fx, fy, p.width, p.height);
  const size_t n = size_t(std::max(0, w.u1 - w.u0));
  std::vector<Vec3> rays(n);
  std::vector<float> reach(n);
  std::vector<RayScene::Hit> hits(n);
  for (int v = w.v0; v < w.v1; ++v) {
    // A row's rays through the pixel centres, with unit depth along the optical axis, cast together.
    for (int u = w.u0; u < w.u1; ++u) {
      rays[size_t(u - w.u0)] = forward + ((float(u) + 0.5f - 0.5f * float(p.width)) / fx) * right +
                               ((0.5f * float(p.height) - float(v) - 0.5f) / fy) * up;
      reach[size_t(u - w.u0)] = p.max_range_m * rays[size_t(u - w.u0)].norm();
    }
    scene.cast_many(pose.position, rays, reach, hits);
    for (size_t k = 0; k < n; ++k) {
      const Vec3& ray = rays[k];
      const float per_depth = ray.norm();  // distance along the ray per metre of depth
      const RayScene::Hit& hit = hits[k];
      if (!hit.hit) continue;
      const Vec3 dir = ray / per_depth;
      const double depth = double(hit.distance) / per_depth;
      if (depth < p.min_range_m) continue;
      if (!returns_at_incidence(-hit.normal.dot(dir), p.dropout_start_deg, p.max_incidence_deg, rng)) continue;
      const double dz = depth - p.noise_c_m;
      const double sigma = p.noise_a_m + p.noise_b_per_m * dz * dz;  // Nguyen et al. 2012, axial
      double z = depth + sigma * standard_normal(rng);
      if (p.disparity_step_px > 0 && focal_baseline > 0) {
        const double disparity = std::round(focal_baseline / z / p.disparity_step_px) * p.disparity_step_px;
        if (!(disparity > 0)) continue;
        z = focal_baseline / disparity;
      }
      out.points.push_back(pose.position + float(z * per_depth) * dir);
    }
  }
  return out;
}

Expected<LidarParams> lidar_with_beams(int beams) {
  LidarParams p;
  p.beams = beams;
  switch (beams) {
    case 16: return p;
    case 32: p.lowest_beam_deg = -25.f, p.highest_beam_deg = 15.f; return p;
    case 64: p.lowest_beam_deg = -24.9f, p.highest_beam_deg = 2.f; return p;
    default: return invalid_argument("a LiDAR has 16, 32 or 64 beams, not " + std::to_string(beams));
  }
}

Cloud lidar_scan(const RayScene& scene, const SensorPose& pose, const LidarParams& p, uint64_t seed) {
  Cloud out;
  out.sensor = pose.position;
  if (p.beams <= 0 || !(p.azimuth_step_deg > 0)) return out;
  const int steps = std::max(1, int(std::lround(360.0 / p.azimuth_step_deg)));
  std::mt19937_64 rng(seed);
  for (int b = 0; b < p.beams; ++b) {
    const float el = (p.beams == 1 ? 0.5f * (p.lowest_beam_deg + p.highest_beam_deg)
                                   : p.lowest_beam_deg + float(b) * (p.highest_beam_deg - p.lowest_beam_deg) /
                                                             float(p.beams - 1)) * kDeg;
    for (int a = 0; a < steps; ++a) {
      const float az = float(a) * 360.f / float(steps) * kDeg;
      const Vec3 dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const RayScene::Hit hit = scene.cast(pose.position, dir, p.max_range_m);
      if (!hit.hit || hit.distance < p.min_range_m) continue;
      if (!returns_at_incidence(-hit.normal.dot(dir), p.max_incidence_deg, p.max_incidence_deg, rng)) continue;
      const double range = hit.distance + p.range_noise_m * standard_normal(rng);
      out.points.push_back(pose.position + float(range) * dir);
    }
  }
  return out;
}

Cloud add_outliers(const Cloud& cloud, double fraction, uint64_t seed) {
  Cloud out = cloud;
  if (cloud.points.empty() || !(fraction > 0)) return out;
  const Bounds b = bounds(cloud.points);
  const float grow = 0.1f * b.extent().norm();
  const Vec3 lo = b.min - Vec3::Constant(grow), size = b.extent() + Vec3::Constant(2 * grow);
  const auto count = static_cast<size_t>(std::llround(fraction * double(cloud.points.size())));
  std::mt19937_64 rng(seed);
  for (size_t i = 0; i < count; ++i) {
    const Vec3 u(float(uniform01(rng)), float(uniform01(rng)), float(uniform01(rng)));
    out.points.push_back(lo + size.cwiseProduct(u));
  }
  return out;
}

}  // namespace glimpse
