#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "glimpse/geometry/floor_plane.h"
#include "glimpse/io/files.h"

namespace glimpse {
namespace {

float degrees_between(const Vec3& a, const Vec3& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.f, 1.f)) * 180.f / std::numbers::pi_v<float>;
}

// `n` points on the patch centre + s u + t v (s, t in [-half, half]) with Gaussian noise along `normal`.
void add_patch(Points& out, const Vec3& centre, const Vec3& u, const Vec3& v, float half, size_t n, float noise_m,
               std::mt19937& rng) {
  std::uniform_real_distribution<float> side(-half, half);
  std::normal_distribution<float> depth(0.f, noise_m);
  const Vec3 normal = u.cross(v).normalized();
  for (size_t i = 0; i < n; ++i) out.push_back(centre + side(rng) * u + side(rng) * v + depth(rng) * normal);
}

// A depth camera at the origin (x right, y down, z forward) looking 40 degrees down at a floor 1.3 m below
// it, with a wall 2.5 m ahead that holds more points than the floor, and missing pixels (NaN).
struct Scene {
  Cloud cloud;
  Vec3 floor_up;  // unit, towards the camera
};
Scene camera_scene(uint64_t seed) {
  std::mt19937 rng{uint32_t(seed)};
  const float pitch = 40.f * std::numbers::pi_v<float> / 180.f;
  // World up and forward in the camera's coordinates: up is -y turned by the pitch towards -z.
  const Vec3 up(0, -std::cos(pitch), -std::sin(pitch)), forward(0, -std::sin(pitch), std::cos(pitch)), right = Vec3::UnitX();
  Scene s{Cloud{}, up};
  add_patch(s.cloud.points, -1.3f * up + 1.8f * forward, right, forward, 1.2f, 3000, 0.005f, rng);  // the floor
  add_patch(s.cloud.points, 2.5f * forward + 0.2f * up, right, up, 1.4f, 5000, 0.005f, rng);         // the wall ahead
  for (int i = 0; i < 500; ++i) s.cloud.points.push_back(Vec3::Constant(std::numeric_limits<float>::quiet_NaN()));
  return s;
}

TEST(FitPlane, FindsTheLargestPlaneAndItsInliers) {
  std::mt19937 rng(3);
  Points points;
  add_patch(points, Vec3(0, 0, 1), Vec3::UnitX(), Vec3(0, 0.6f, 0.8f), 1.f, 400, 0.002f, rng);
  std::uniform_real_distribution<float> box(-2.f, 2.f);
  for (int i = 0; i < 100; ++i) points.emplace_back(box(rng), box(rng), box(rng) + 3.f);  // clutter off the plane
  std::vector<uint32_t> all(points.size()), inliers;
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  const std::optional<Plane> plane = fit_plane(points, all, PlaneFitParams{}, &inliers);
  ASSERT_TRUE(plane.has_value());
  EXPECT_LT(std::min(degrees_between(plane->normal, Vec3(0, -0.8f, 0.6f)), degrees_between(-plane->normal, Vec3(0, -0.8f, 0.6f))), 0.5f);
  EXPECT_NEAR(plane->normal.norm(), 1.f, 1e-5f);
  ASSERT_EQ(inliers.size(), plane->inliers);
  size_t on_patch = 0;
  for (uint32_t i : inliers) {
    EXPECT_LT(std::abs(plane->normal.dot(points[i]) + plane->offset), PlaneFitParams{}.distance_m);
    on_patch += i < 400;
  }
  EXPECT_GE(on_patch, 396u);  // the patch, and the few clutter points that happen to lie on it
  EXPECT_LE(inliers.size(), 410u);
  // Three points make a plane; two do not.
  EXPECT_TRUE(fit_plane(points, {0, 1, 2}, PlaneFitParams{}).has_value());
  EXPECT_FALSE(fit_plane(points, {0, 1}, PlaneFitParams{}).has_value());
}

TEST(FitPlane, AnAxisPicksThePlaneFacingIt) {
  std::mt19937 rng(4);
  Points points;
  add_patch(points, Vec3(0, 0, 0), Vec3::UnitX(), Vec3::UnitY(), 1.f, 300, 0.002f, rng);  // horizontal, smaller
  add_patch(points, Vec3(0, 2, 1.5f), Vec3::UnitX(), Vec3::UnitZ(), 1.f, 600, 0.002f, rng);  // vertical, larger
  std::vector<uint32_t> all(points.size());
  for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
  const std::optional<Plane> any = fit_plane(points, all, PlaneFitParams{});
  ASSERT_TRUE(any.has_value());
  EXPECT_GT(std::abs(any->normal.y()), 0.99f);
  const std::optional<Plane> level = fit_plane(points, all, PlaneFitParams{0.02f, 1000, Vec3::UnitZ(), 10.f});
  ASSERT_TRUE(level.has_value());
  EXPECT_GT(std::abs(level->normal.z()), 0.99f);
  EXPECT_EQ(level->inliers, 300u);
}

TEST(FloorUp, FindsTheFloorTheCameraLooksDownOnNotTheLargerWall) {
  const Scene scene = camera_scene(7);
  Expected<Vec3> up = floor_up(scene.cloud);
  ASSERT_TRUE(up.ok()) << up.error().message;
  EXPECT_LT(degrees_between(*up, scene.floor_up), 1.f) << up->transpose();
  EXPECT_NEAR(up->norm(), 1.f, 1e-5f);
  Expected<Vec3> again = floor_up(scene.cloud);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(*again, *up);  // deterministic
}

TEST(FloorUp, PointsToTheSensorsSide) {
  Scene scene = camera_scene(8);
  scene.cloud.sensor = Vec3::Zero();
  Expected<Vec3> from_above = floor_up(scene.cloud);
  ASSERT_TRUE(from_above.ok()) << from_above.error().message;
  EXPECT_LT(degrees_between(*from_above, scene.floor_up), 1.f);
  // A sensor under the floor looks up at it: the floor's other side faces it. The image's up (its frame)
  // turns with it, else the floor would be a ceiling.
  scene.cloud.sensor = -3.f * scene.floor_up;
  scene.cloud.frame = CameraFrame{Vec3::UnitZ(), scene.floor_up, 57, 43};
  Expected<Vec3> from_below = floor_up(scene.cloud);
  ASSERT_FALSE(from_below.ok());  // the floor is above this camera, the wall on its side: no floor below
  scene.cloud.frame->up = -scene.floor_up;
  from_below = floor_up(scene.cloud);
  ASSERT_TRUE(from_below.ok()) << from_below.error().message;
  EXPECT_LT(degrees_between(*from_below, -scene.floor_up), 1.f);
}

TEST(FloorUp, NoFloorIsAnError) {
  std::mt19937 rng(9);
  Cloud wall;  // straight ahead of the camera: its normal is 90 degrees from the image's up
  add_patch(wall.points, Vec3(0, 0, 2), Vec3::UnitX(), Vec3::UnitY(), 1.f, 2000, 0.003f, rng);
  Expected<Vec3> up = floor_up(wall);
  ASSERT_FALSE(up.ok());
  EXPECT_EQ(up.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(up.error().message.find("no floor"), std::string::npos) << up.error().message;
  Cloud nothing;
  nothing.points.assign(10, Vec3::Constant(std::numeric_limits<float>::quiet_NaN()));
  EXPECT_FALSE(floor_up(nothing).ok());
  EXPECT_FALSE(floor_up(Cloud{}).ok());
}

// ---- real frames (../shared/data/real-scenes: their README gives each frame's floor / table normal) ----

std::string real_scenes_dir() {
  if (const char* env = std::getenv("GLIMPSE_REAL_SCENES_DIR")) return env;
  return GLIMPSE_SOURCE_DIR "/../shared/data/real-scenes";
}

TEST(FloorUp, RealFramesWithinTwoDegreesOfTheirTable) {
  const std::string dir = real_scenes_dir();
  if (!std::filesystem::is_directory(dir))
    GTEST_SKIP() << "real scenes not found at " << dir << " (set GLIMPSE_REAL_SCENES_DIR)";
  const Vec3 desk(0.072f, -0.692f, -0.718f), tabletop(0.005f, -0.821f, -0.571f);
  const std::vector<std::pair<std::string, Vec3>> frames = {{"desk_laptop_box_frame0.pcd", desk},
                                                            {"desk_laptop_box_frame1.pcd", desk},
                                                            {"desk_laptop_box_frame2.pcd", desk},
                                                            {"tabletop_milk_bleach_detergent.pcd", tabletop}};
  for (const auto& [name, expected] : frames) {
    SCOPED_TRACE(name);
    Expected<Cloud> cloud = read_cloud(dir + "/" + name);
    ASSERT_TRUE(cloud.ok()) << cloud.error().message;
    Expected<Vec3> up = floor_up(*cloud);
    ASSERT_TRUE(up.ok()) << up.error().message;
    const float error = degrees_between(*up, expected);
    std::printf("%s: floor up (%.3f, %.3f, %.3f), %.2f degrees from the README's\n", name.c_str(), up->x(), up->y(),
                up->z(), error);
    EXPECT_LT(error, 2.f);
  }
}

}  // namespace
}  // namespace glimpse
