// The simulated sensors' geometry against values worked out by hand: the depth camera's noise on a
// plane (Nguyen et al.'s sigma(z)), its disparity grid, incidence dropouts, density against distance;
// the LiDAR's beam rings and range noise; the floor patch; outliers; determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <thread>

#include "glimpse/views/sensors.h"
#include "glimpse/views/zoo.h"

namespace glimpse {
namespace {

constexpr float kDeg = 3.14159265f / 180.f;

// A square of half-size h in the plane x = x0 (normal along x), optionally turned about z by `turn_deg`.
Mesh wall(float x0, float h, float turn_deg = 0) {
  Mesh m;
  const float c = std::cos(turn_deg * kDeg), s = std::sin(turn_deg * kDeg);
  for (auto [y, z] : {std::pair{-h, -h}, {h, -h}, {h, h}, {-h, h}})
    m.vertices.emplace_back(x0 - s * y, c * y, z);
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

// UV sphere, `rings` x `segments`.
Mesh sphere_mesh(float radius, Vec3 centre, int rings = 40, int segments = 80) {
  Mesh m;
  for (int i = 0; i <= rings; ++i) {
    const float t = 3.14159265f * float(i) / float(rings);
    for (int j = 0; j < segments; ++j) {
      const float p = 2 * 3.14159265f * float(j) / float(segments);
      m.vertices.push_back(centre + radius * Vec3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)));
    }
  }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * segments + j, b = i * segments + (j + 1) % segments;
      m.faces.emplace_back(a, a + segments, b);
      m.faces.emplace_back(b, a + segments, b + segments);
    }
  return m;
}

DepthCameraParams noiseless() {
  DepthCameraParams p;
  p.noise_a_m = p.noise_b_per_m = 0;
  p.disparity_step_px = 0;
  return p;
}

double mean_x(const Points& p) {
  double s = 0;
  for (const Vec3& v : p) s += v.x();
  return s / double(p.size());
}

double std_x(const Points& p) {
  const double m = mean_x(p);
  double s = 0;
  for (const Vec3& v : p) s += (v.x() - m) * (v.x() - m);
  return std::sqrt(s / double(p.size() - 1));
}

TEST(RayScene, CastFindsTheNearestSurfaceAndItsNormal) {
  auto scene = RayScene::build(wall(2.f, 1.f));
  ASSERT_TRUE(scene.ok()) << scene.error().message;
  const RayScene::Hit hit = scene->cast(Vec3::Zero(), Vec3(2, 0, 0), 10.f);  // dir need not be unit
  ASSERT_TRUE(hit.hit);
  EXPECT_NEAR(hit.distance, 2.f, 1e-5);
  EXPECT_NEAR(hit.normal.x(), -1.f, 1e-5);  // faces the origin
  EXPECT_FALSE(hit.floor);
  EXPECT_FALSE(scene->cast(Vec3::Zero(), Vec3(1, 0, 0), 1.5f).hit);   // beyond max_distance
  EXPECT_FALSE(scene->cast(Vec3::Zero(), Vec3(-1, 0, 0), 10.f).hit);  // behind
}

TEST(RayScene, BadMeshesAreClearErrors) {
  EXPECT_FALSE(RayScene::build(Mesh{}).ok());
  Mesh m = wall(2.f, 1.f);
  m.faces.push_back({0, 1, 7});
  auto r = RayScene::build(m);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("vertex that does not exist"), std::string::npos);
  m = wall(2.f, 1.f);
  m.vertices[0].x() = NAN;
  EXPECT_FALSE(RayScene::build(m).ok());
}

TEST(RayScene, FloorPatchLiesAtZeroUnderTheObject) {
  Mesh m = sphere_mesh(0.3f, {5.f, 0.f, 0.3f});
  auto scene = RayScene::build(m, 1.f);
  ASSERT_TRUE(scene.ok());
  const RayScene::Hit down = scene->cast({4.2f, 0.f, 1.f}, {0, 0, -1}, 10.f);  // beside the sphere
  ASSERT_TRUE(down.hit);
  EXPECT_TRUE(down.floor);
  EXPECT_NEAR(down.distance, 1.f, 1e-5);
  EXPECT_FALSE(scene->cast({3.8f, 0.f, 1.f}, {0, 0, -1}, 10.f).hit);  // beyond the 1 m patch
}

// Packets of 8 rays find what single rays find: a sphere on the floor seen through a camera's pixel
// grid (hits on both, misses, grazing rays at the silhouette), a count of rays that leaves the last
// packet part-filled, a zero direction and a zero reach (no hit, as cast() says). Where two faces lie
// at the same distance (an edge, a duplicated face) either may be reported: this sphere has none.
TEST(RayScene, CastManyFindsWhatCastFindsRayByRay) {
  auto scene = RayScene::build(sphere_mesh(0.3f, {0.f, 0.f, 0.3f}), 1.f);
  ASSERT_TRUE(scene.ok());
  const Vec3 origin(1.2f, 0.3f, 0.8f);
  std::vector<Vec3> dirs;
  std::vector<float> reach;
  for (int v = 0; v < 61; ++v)
    for (int u = 0; u < 61; ++u) {
      dirs.push_back(Vec3(-1.f, 0.02f * float(u - 30), 0.02f * float(v - 45)) - Vec3(0, 0.25f, 0));
      reach.push_back(u % 17 == 3 ? 1.f : 4.f);  // some rays stop short of the sphere's far side
    }
  dirs.push_back(Vec3::Zero()), reach.push_back(4.f);
  dirs.push_back(Vec3(-1, 0, -0.5f)), reach.push_back(0.f);
  ASSERT_NE(dirs.size() % 8, 0u);
  std::vector<RayScene::Hit> many(dirs.size());
  scene->cast_many(origin, dirs, reach, many);
  size_t hits = 0, floor = 0;
  for (size_t i = 0; i < dirs.size(); ++i) {
    const RayScene::Hit one = scene->cast(origin, dirs[i], reach[i]);
    ASSERT_EQ(many[i].hit, one.hit) << "ray " << i;
    EXPECT_EQ(many[i].distance, one.distance) << "ray " << i;
    EXPECT_EQ(many[i].normal, one.normal) << "ray " << i;
    EXPECT_EQ(many[i].floor, one.floor) << "ray " << i;
    hits += one.hit, floor += one.floor;
  }
  EXPECT_GT(hits - floor, 300u);  // the sphere and the floor both seen, and rays that miss both
  EXPECT_GT(floor, 300u);
  EXPECT_LT(hits, dirs.size() - 300);
  EXPECT_FALSE(many[dirs.size() - 2].hit);
  EXPECT_FALSE(many.back().hit);
}

TEST(DepthCamera, PlaneAtTwoMetresHasNguyensAxialSigma) {
  // Camera at the origin looking along +x at a 6 m wide wall 2 m away: every pixel has depth 2 m.
  auto scene = RayScene::build(wall(2.f, 3.f));
  ASSERT_TRUE(scene.ok());
  DepthCameraParams p;
  p.disparity_step_px = 0;  // the noise alone
  const Cloud c = depth_camera_scan(*scene, {Vec3::Zero(), Vec3(1, 0, 0)}, p, 7);
  ASSERT_EQ(c.points.size(), size_t(640 * 480));  // the wall fills the image, incidence < 70 deg
  ASSERT_TRUE(c.sensor.has_value());
  // sigma(2) = 1.2 mm + 1.9 mm (2 - 0.4)^2 = 6.064 mm; depth is x here.
  EXPECT_NEAR(mean_x(c.points), 2.0, 1e-4);
  EXPECT_NEAR(std_x(c.points), 0.006064, 0.006064 * 0.02);
}

TEST(DepthCamera, DepthsLieOnTheDisparityGrid) {
  auto scene = RayScene::build(wall(2.f, 3.f));
  ASSERT_TRUE(scene.ok());
  DepthCameraParams p;  // Kinect defaults: 1/8 px disparity steps
  const Cloud c = depth_camera_scan(*scene, {Vec3::Zero(), Vec3(1, 0, 0)}, p, 7);
  const double fx = 320.0 / std::tan(28.5 * 3.141592653589793 / 180.0), bf = fx * 0.075;
  std::set<long> steps;
  size_t off_grid = 0;
  for (const Vec3& v : c.points) {
    const double d = bf / v.x() / 0.125;  // disparity in 1/8 px
    off_grid += std::abs(d - std::round(d)) > 2e-3;
    steps.insert(std::lround(d));
  }
  EXPECT_EQ(off_grid, 0u);
  // At 2 m one disparity step is z^2 / (f b) / 8 = 11.3 mm, about 2 sigma: a few distinct depths.
  EXPECT_GE(steps.size(), 3u);
  EXPECT_LE(steps.size(), 12u);
}

TEST(DepthCamera, GrazingSurfacesLoseTheirReturns) {
  // The wall turned so the optical axis meets it at 60, 78 and 88 degrees (start 70, max 85).
  auto count = [](float turn) {
    auto scene = RayScene::build(wall(2.f, 3.f, turn));
    EXPECT_TRUE(scene.ok());
    DepthCameraParams p = noiseless();
    p.width = 64, p.height = 48, p.fov_h_deg = 4.f, p.fov_v_deg = 3.f;  // a narrow cone about the axis
    return double(depth_camera_scan(*scene, {Vec3::Zero(), Vec3(1, 0, 0)}, p, 3).points.size()) / (64.0 * 48.0);
  };
  EXPECT_NEAR(count(60.f), 1.0, 1e-9);
  // Within +-2 degrees of 78: the keep probability 1 - (78 - 70) / 15 = 0.47 (0.33..0.6 over the cone).
  EXPECT_NEAR(count(78.f), 0.47, 0.08);
  EXPECT_EQ(count(88.f), 0.0);
}

TEST(DepthCamera, DensityFallsWithTheSquareOfDistance) {
  // A sphere of radius r at distance d on the optical axis images as a disc of radius tan(asin(r / d))
  // focal lengths: fx fy pi tan^2(asin(r / d)) pixels, nearly 1/d^2.
  const float r = 0.3f;
  DepthCameraParams p = noiseless();
  p.dropout_start_deg = p.max_incidence_deg = 90.f;  // the rim too
  auto points_at = [&](float d) {
    auto scene = RayScene::build(sphere_mesh(r, {d, 0.f, 0.f}, 80, 160));
    EXPECT_TRUE(scene.ok());
    return double(depth_camera_scan(*scene, {Vec3::Zero(), Vec3(d, 0, 0)}, p, 1).points.size());
  };
  const double fx = 320.0 / std::tan(28.5 * kDeg), fy = 240.0 / std::tan(21.5 * kDeg);
  auto pixels = [&](double d) {
    const double t = std::tan(std::asin(double(r) / d));
    return fx * fy * 3.14159265358979 * t * t;
  };
  for (float d : {1.f, 2.f, 3.f}) EXPECT_NEAR(points_at(d), pixels(d), 0.02 * pixels(d)) << d << " m";
  EXPECT_GT(points_at(3.f), 1000);  // still a usable view at 3 m
}

TEST(DepthCamera, RangeLimitsAndSameSeedSameCloud) {
  auto scene = RayScene::build(wall(5.f, 6.f));
  ASSERT_TRUE(scene.ok());
  EXPECT_TRUE(depth_camera_scan(*scene, {Vec3::Zero(), Vec3(1, 0, 0)}, {}, 1).points.empty());  // 5 m > 4.5 m
  auto near = RayScene::build(wall(2.f, 3.f));
  ASSERT_TRUE(near.ok());
  const Cloud a = depth_camera_scan(*near, orbit_pose({2, 0, 0}, 180.f, 10.f, 2.f), {}, 11);
  Cloud b;
  std::thread t([&] { b = depth_camera_scan(*near, orbit_pose({2, 0, 0}, 180.f, 10.f, 2.f), {}, 11); });
  t.join();
  EXPECT_EQ(a.points, b.points);
  const Cloud c = depth_camera_scan(*near, orbit_pose({2, 0, 0}, 180.f, 10.f, 2.f), {}, 12);
  EXPECT_NE(a.points, c.points);
}

// The camera casts only the pixels whose rays can reach the scene's bounds: the same points, bit for bit,
// as casting every pixel, from near, far, level and high, with and without a floor.
TEST(DepthCamera, CastingOnlyTheWindowOntoTheSceneGivesTheWholeFramesPoints) {
  const Mesh chair = *make_zoo_shape("chair", 3);
  const Vec3 centre = bounds(chair.vertices).centre();
  DepthCameraParams every_pixel;
  every_pixel.whole_frame = true;
  for (auto [distance, elevation] : {std::pair{1.2f, 15.f}, {3.f, 45.f}, {2.f, 0.f}, {4.f, 70.f}})
    for (float floor : {0.f, 1.5f}) {
      const SensorPose pose = orbit_pose(centre, 40.f, elevation, distance);
      auto scene = RayScene::build(chair, floor);
      ASSERT_TRUE(scene.ok());
      const Cloud a = depth_camera_scan(*scene, pose, {}, 5), b = depth_camera_scan(*scene, pose, every_pixel, 5);
      EXPECT_GT(a.points.size(), 1000u) << distance << " m, " << elevation << " deg, floor " << floor;
      EXPECT_EQ(a.points, b.points) << distance << " m, " << elevation << " deg, floor " << floor;
    }
  // A plate square to the camera fills its bounds' window to the edge: any pixel short is a point short.
  auto plate = RayScene::build(wall(2.f, 0.3f, 20.f));
  ASSERT_TRUE(plate.ok());
  const SensorPose facing{Vec3::Zero(), Vec3(2, 0, 0)};
  const Cloud a = depth_camera_scan(*plate, facing, {}, 6), b = depth_camera_scan(*plate, facing, every_pixel, 6);
  EXPECT_GT(a.points.size(), 10000u);
  EXPECT_EQ(a.points, b.points);
}

TEST(OrbitPose, PlacesTheSensorAtDistanceAndElevation) {
  const SensorPose p = orbit_pose({1, 2, 0.5f}, 90.f, 30.f, 4.f);
  EXPECT_NEAR((p.position - p.target).norm(), 4.f, 1e-5);
  EXPECT_NEAR(p.position.z() - 0.5f, 4.f * std::sin(30 * kDeg), 1e-5);
  EXPECT_NEAR(p.position.x(), 1.f, 1e-5);  // azimuth 90: along +y
  EXPECT_GT(p.position.y(), 2.f);
}

TEST(Lidar, BeamsMakeRingsWithTheStatedSpacingAndNoise) {
  // A 20 m tall wall 10 m away: 16 beams from -15 to +15 deg, 2 deg apart -> 16 horizontal lines,
  // z = 10 tan(elevation); range noise 1.5 cm shows as x spread for near-perpendicular beams.
  auto scene = RayScene::build(wall(10.f, 10.f));
  ASSERT_TRUE(scene.ok());
  const LidarParams lp;
  const Cloud c = lidar_scan(*scene, {Vec3::Zero(), Vec3(1, 0, 0)}, lp, 5);
  ASSERT_FALSE(c.points.empty());
  std::set<long> rings;
  Points central;
  for (const Vec3& p : c.points) {
    const double el = std::atan2(p.z(), std::hypot(p.x(), p.y())) / kDeg;
    rings.insert(std::lround((el + 15.0) / 2.0));
    EXPECT_NEAR(el, -15.0 + 2.0 * std::round((el + 15.0) / 2.0), 0.2);
    if (std::abs(p.y()) < 0.5f && std::abs(p.z()) < 0.5f) central.push_back(p);
  }
  EXPECT_EQ(rings.size(), 16u);
  // Azimuths hitting the wall: |atan(y / 10)| < atan(1) = 45 deg -> 90 deg / 0.2 deg = 450 per beam.
  EXPECT_NEAR(double(c.points.size()), 16 * 450.0, 16 * 3.0);
  ASSERT_GT(central.size(), 20u);
  EXPECT_NEAR(std_x(central), 0.015, 0.006);
}

TEST(Lidar, ThirtyTwoAndSixtyFourBeamsSpanTheirClassesFieldsAndOtherCountsAreErrors) {
  // The same wall: 32 beams over -25..15 deg (1.29 deg apart), 64 over -24.9..2 deg (0.43 deg apart);
  // every beam below 45 deg meets a wall 10 m away that is 20 m tall.
  auto scene = RayScene::build(wall(10.f, 10.f));
  ASSERT_TRUE(scene.ok());
  for (int beams : {32, 64}) {
    auto lp = lidar_with_beams(beams);
    ASSERT_TRUE(lp.ok()) << lp.error().message;
    const Cloud c = lidar_scan(*scene, {Vec3::Zero(), Vec3(1, 0, 0)}, *lp, 5);
    std::set<long> rings;
    double lowest = 90, highest = -90;
    for (const Vec3& p : c.points) {
      const double el = std::atan2(p.z(), std::hypot(p.x(), p.y())) / kDeg;
      rings.insert(std::lround((el - lp->lowest_beam_deg) / ((lp->highest_beam_deg - lp->lowest_beam_deg) / (beams - 1))));
      lowest = std::min(lowest, el), highest = std::max(highest, el);
    }
    EXPECT_EQ(rings.size(), size_t(beams)) << beams;
    EXPECT_NEAR(lowest, beams == 32 ? -25.0 : -24.9, 0.1) << beams;
    EXPECT_NEAR(highest, beams == 32 ? 15.0 : 2.0, 0.1) << beams;
    EXPECT_NEAR(double(c.points.size()), beams * 450.0, beams * 3.0);
  }
  EXPECT_TRUE(lidar_with_beams(16).ok());
  for (int bad : {0, 8, 128}) {
    auto lp = lidar_with_beams(bad);
    ASSERT_FALSE(lp.ok()) << bad;
    EXPECT_NE(lp.error().message.find("16, 32 or 64"), std::string::npos) << lp.error().message;
  }
}

TEST(Lidar, FarObjectsGetFewerPoints) {
  auto count = [](float d) {
    auto scene = RayScene::build(sphere_mesh(0.5f, {d, 0.f, 0.f}));
    EXPECT_TRUE(scene.ok());
    return lidar_scan(*scene, {Vec3::Zero(), Vec3(1, 0, 0)}, {}, 1).points.size();
  };
  const size_t n5 = count(5.f), n15 = count(15.f);
  // At 5 m the sphere spans +-5.7 deg: 5-6 beams x ~57 azimuth steps; at 15 m +-1.9 deg: 1-2 beams x ~19.
  EXPECT_GT(n5, 200u);
  EXPECT_LT(n15, n5 / 4);
}

TEST(Outliers, AddTheFractionInsideTheGrownBox) {
  Cloud c;
  for (int i = 0; i < 1000; ++i) c.points.emplace_back(float(i % 10) * 0.1f, float(i / 100) * 0.1f, 0.5f);
  c.sensor = Vec3(0, 0, 3);
  const Cloud o = add_outliers(c, 0.05, 9);
  ASSERT_EQ(o.points.size(), 1050u);
  EXPECT_EQ(o.sensor, c.sensor);
  const Bounds b = bounds(c.points);
  const float grow = 0.1f * b.extent().norm();
  size_t off_plane = 0;
  for (size_t i = 1000; i < o.points.size(); ++i) {
    EXPECT_TRUE((o.points[i].array() >= (b.min.array() - grow - 1e-5f)).all());
    EXPECT_TRUE((o.points[i].array() <= (b.max.array() + grow + 1e-5f)).all());
    off_plane += std::abs(o.points[i].z() - 0.5f) > 1e-3f;
  }
  EXPECT_GT(off_plane, 40u);
  EXPECT_EQ(add_outliers(c, 0.05, 9).points, o.points);
}

}  // namespace
}  // namespace glimpse
