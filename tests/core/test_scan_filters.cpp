// Scan filters on synthetic scenes with a known answer: the floor goes and nothing else (also tilted,
// also under a table whose top is a larger horizontal plane), stray points go, the voxel grid gives the
// density asked for, and the relative density is the same for grids, random samples and any scale.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "glimpse/geometry/scan_filters.h"

namespace glimpse {
namespace {

// A square grid of half-size h and spacing s at height z (turned about x by tilt_deg).
Points grid_plane(float h, float s, float z = 0, float tilt_deg = 0) {
  Points p;
  const float t = tilt_deg * 3.14159265f / 180.f;
  const int n = int(std::lround(2 * h / s));
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const float x = -h + float(i) * s, y = -h + float(j) * s;
      p.emplace_back(x, std::cos(t) * y, z + std::sin(t) * y);
    }
  return p;
}

Points sphere_points(float r, Vec3 c, size_t n) {
  Points p;
  const float golden = 3.14159265f * (3.f - std::sqrt(5.f));
  for (size_t i = 0; i < n; ++i) {
    const float z = 1.f - 2.f * (float(i) + 0.5f) / float(n), rho = std::sqrt(1.f - z * z), a = golden * float(i);
    p.push_back(c + r * Vec3(rho * std::cos(a), rho * std::sin(a), z));
  }
  return p;
}

Cloud concat(const Points& a, const Points& b) {
  Cloud c;
  c.points = a;
  c.points.insert(c.points.end(), b.begin(), b.end());
  c.sensor = Vec3(3, 0, 2);
  return c;
}

TEST(GroundPlane, TheFloorGoesAndTheObjectStays) {
  const Points floor = grid_plane(1.f, 0.02f);  // 101 x 101
  const Points ball = sphere_points(0.3f, {0, 0, 0.35f}, 3000);  // 5 cm above the floor
  size_t removed = 0;
  const Cloud out = remove_ground_plane(concat(floor, ball), {}, &removed);
  EXPECT_EQ(removed, floor.size());
  EXPECT_EQ(out.points, ball);
  EXPECT_EQ(out.sensor, Vec3(3, 0, 2));
}

TEST(GroundPlane, ATiltedFloorGoesToo) {
  const Points floor = grid_plane(1.f, 0.02f, 0.f, 5.f);  // a 5 degree error in the up vector
  const Points ball = sphere_points(0.3f, {0, 0, 0.5f}, 3000);
  size_t removed = 0;
  remove_ground_plane(concat(floor, ball), {}, &removed);
  EXPECT_EQ(removed, floor.size());
}

TEST(GroundPlane, NoFloorNothingRemovedEvenUnderALargeTableTop) {
  // A table: a 1 x 1 m top at 0.75 m (2601 points) on four legs; no floor. The top is the largest
  // horizontal plane but not the ground; the legs' feet are too few to be one.
  Points table = grid_plane(0.5f, 0.02f, 0.75f);
  for (float x : {-0.45f, 0.45f})
    for (float y : {-0.45f, 0.45f})
      for (int k = 0; k < 75; ++k) table.emplace_back(x, y, float(k) * 0.01f);
  size_t removed = 1;
  const Cloud out = remove_ground_plane(concat(table, {}), {}, &removed);
  EXPECT_EQ(removed, 0u);
  EXPECT_EQ(out.points.size(), table.size());
  // With a floor under it, the floor goes and the table (legs to 1.5 cm above it) stays.
  const Points floor = grid_plane(1.f, 0.02f);
  remove_ground_plane(concat(floor, table), {}, &removed);
  EXPECT_GE(removed, floor.size());
  EXPECT_LE(removed, floor.size() + 4 * 5);  // at most the legs' lowest 4 cm (z = 0, 1, 2, 3, 4 cm)
}

TEST(GroundPlane, ABasePlateOfTheObjectIsNotAFloor) {
  // A post on a base plate (a part's flange): horizontal, lowest, carries the object, but reaches only
  // 2 cm beyond the post's footprint (the margin is 5 cm): it stays.
  Points part = grid_plane(0.07f, 0.005f, 0.01f);  // 0.14 m plate, 1 cm thick
  for (int k = 0; k < 400; ++k)                      // a 0.1 m post, 0.4 m tall
    for (int a = 0; a < 12; ++a)
      part.emplace_back(0.05f * std::cos(float(a) * 0.5236f), 0.05f * std::sin(float(a) * 0.5236f), 0.01f + float(k) * 0.001f);
  size_t removed = 1;
  remove_ground_plane(concat(part, {}), {}, &removed);
  EXPECT_EQ(removed, 0u);
}

TEST(GroundPlane, AStarBaseIsNotAFloor) {
  // An office chair: five 3 cm bars radiating 0.35 m from a column under a 0.45 m seat.
  Points chair = grid_plane(0.225f, 0.01f, 0.45f);
  for (int bar = 0; bar < 5; ++bar) {
    const float a = float(bar) * 1.2566f;
    for (float r = 0; r <= 0.35f; r += 0.01f)
      for (float w = -0.015f; w <= 0.015f; w += 0.01f)
        chair.emplace_back(r * std::cos(a) - w * std::sin(a), r * std::sin(a) + w * std::cos(a), 0.02f);
  }
  for (float z = 0.03f; z < 0.45f; z += 0.005f)
    for (int k = 0; k < 8; ++k) chair.emplace_back(0.03f * std::cos(float(k) * 0.785f), 0.03f * std::sin(float(k) * 0.785f), z);
  size_t removed = 1;
  remove_ground_plane(concat(chair, {}), {}, &removed);
  EXPECT_EQ(removed, 0u);
  // On a floor, the floor goes (and the bars with it: they lie within its inlier distance).
  const Points floor = grid_plane(1.f, 0.02f);
  remove_ground_plane(concat(floor, chair), {}, &removed);
  EXPECT_GE(removed, floor.size());
}

TEST(FilterScan, StrayPointsUnderTheFloorDoNotHideIt) {
  Points floor = grid_plane(1.f, 0.02f);
  const Points ball = sphere_points(0.3f, {0, 0, 0.35f}, 3000);
  Points stray = {{0.5f, 0.5f, -0.6f}, {-0.4f, 0.2f, -0.9f}, {0.1f, -0.7f, -0.4f}};
  Cloud scene = concat(floor, ball);
  scene.points.insert(scene.points.end(), stray.begin(), stray.end());
  ScanFilterReport r;
  const Cloud out = filter_scan(scene, {}, &r);
  EXPECT_EQ(r.outliers, stray.size());
  EXPECT_EQ(r.ground, floor.size());
  EXPECT_EQ(out.points, ball);
}

TEST(IsolatedPoints, StrayPointsGoTheSurfaceStays) {
  const Points surface = sphere_points(0.5f, {0, 0, 1}, 5000);
  Points stray;
  std::mt19937_64 rng(3);
  for (int i = 0; i < 25; ++i) {
    const Vec3 d = Vec3(float(rng() % 1000) - 500.f, float(rng() % 1000) - 500.f, float(rng() % 1000) - 500.f).normalized();
    stray.push_back(Vec3(0, 0, 1) + (0.9f + 0.02f * float(i)) * d);  // 0.4-0.9 m off the surface
  }
  size_t removed = 0;
  const Cloud out = remove_isolated_points(concat(surface, stray), 5.f, 2, &removed);
  EXPECT_EQ(removed, stray.size());
  for (const Vec3& p : out.points) EXPECT_NEAR((p - Vec3(0, 0, 1)).norm(), 0.5f, 1e-4f);
}

TEST(VoxelGrid, OnePointPerOccupiedVoxel) {
  const Cloud dense = concat(grid_plane(0.15f, 0.001f, 0.0005f), {});  // 301 x 301, 1 mm apart
  const Cloud out = voxel_downsample(dense, 0.01f);
  // 0.3 m / 1 cm: 30 (or 31 with a sliver at the edge) voxels a side.
  EXPECT_GE(out.points.size(), 30u * 30u);
  EXPECT_LE(out.points.size(), 32u * 32u);
  EXPECT_EQ(out.sensor, dense.sensor);
  EXPECT_EQ(voxel_downsample(dense, 0.f).points.size(), dense.points.size());
}

// A few points 50 m away make the grid 3000 voxels a side at 1 cm: 2.7e10 voxels, past PCL's 32-bit index,
// where VoxelGrid gives the input back unchanged. The leaf grows until it fits, and the cloud is thinned.
TEST(VoxelGrid, AWideCloudIsThinnedNotReturnedWhole) {
  Cloud wide = concat(grid_plane(0.1f, 0.001f, 0.0005f), {});  // 201 x 201, 1 mm apart
  for (int i = 0; i < 10; ++i) wide.points.emplace_back(30.f + 0.01f * float(i), 30.f, 30.f);
  const Cloud out = voxel_downsample(wide, 0.01f);
  EXPECT_LT(out.points.size(), wide.points.size() / 10);
  EXPECT_GE(out.points.size(), 2u);  // the patch and the far points are still there
}

TEST(RelativeDensity, SameForGridsRandomSamplesAndAnyScale) {
  // 1 m square at 1 cm spacing: 10^4 points per m^2, extent 1 m -> about 10^4.
  const Points grid = grid_plane(0.5f, 0.01f);
  EXPECT_NEAR(relative_density(grid), 1.0e4, 0.15e4);
  Points random;
  std::mt19937_64 rng(1);
  for (int i = 0; i < 10000; ++i)
    random.emplace_back(float(rng() >> 11) * 0x1.0p-53f - 0.5f, float(rng() >> 11) * 0x1.0p-53f - 0.5f, 0.f);
  EXPECT_NEAR(relative_density(random), 1.0e4, 0.2e4);
  Points big = grid;
  for (Vec3& p : big) p *= 10.f;
  EXPECT_NEAR(relative_density(big), relative_density(grid), 1e-3 * relative_density(grid));
  EXPECT_EQ(relative_density(Points(5, Vec3::Zero())), 0.0);
}

TEST(FilterScan, BringsADenseCloudToTheTrainedDensityAndLeavesOthersAlone) {
  ScanFilterParams p;
  p.relative_density = 2500;  // 1 m square at 2 cm
  const Cloud dense = concat(grid_plane(0.5f, 0.005f), {});  // 16x denser
  ScanFilterReport r;
  const Cloud out = filter_scan(dense, p, &r);
  EXPECT_GT(r.voxel_m, 0.f);
  EXPECT_EQ(r.input, dense.points.size());
  EXPECT_EQ(r.kept, out.points.size());
  EXPECT_NEAR(relative_density(out.points), 2500, 0.3 * 2500);
  // A table top alone, as the first points of a top-down scan show it, at the trained density: no
  // ground (nothing stands on it), no voxel grid.
  Cloud top = concat(grid_plane(0.5f, 0.02f, 0.75f), {});
  std::mt19937_64 rng(5);  // a sensor's noise: 2 mm
  for (Vec3& v : top.points) v += 0.002f * Vec3(float(rng() % 1000) / 500.f - 1.f, float(rng() % 1000) / 500.f - 1.f, float(rng() % 1000) / 500.f - 1.f);
  const Cloud kept = filter_scan(top, p, &r);
  EXPECT_EQ(r.voxel_m, 0.f);
  EXPECT_EQ(r.ground, 0u);
  EXPECT_EQ(kept.points.size(), top.points.size() - r.outliers);
  EXPECT_EQ(r.outliers, 0u);  // its border included
}

}  // namespace
}  // namespace glimpse
