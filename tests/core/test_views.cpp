#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <thread>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "glimpse/views/sampling.h"
#include "glimpse/views/placement.h"
#include "glimpse/views/hidden_point_removal.h"
#include "glimpse/views/exploration.h"

namespace glimpse {
namespace {

constexpr double kPi = 3.14159265358979323846;

Mesh unit_square() {  // z = 0, area 1
  Mesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  m.faces = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
  return m;
}

Mesh unit_cube() {  // [0,1]^3, outward faces
  Mesh m;
  for (int i = 0; i < 8; ++i) m.vertices.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.faces.emplace_back(q[0], q[1], q[2]);
    m.faces.emplace_back(q[0], q[2], q[3]);
  }
  return m;
}

Points fibonacci_sphere(size_t n, float radius, const Vec3& centre) {
  Points pts;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (size_t i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (double(i) + 0.5) / double(n);
    const double r = std::sqrt(1.0 - z * z);
    pts.push_back(centre + radius * Vec3(float(r * std::cos(golden * i)), float(r * std::sin(golden * i)), float(z)));
  }
  return pts;
}

// ---- points from a mesh ----

TEST(MeshVertices, AreTheVertices) {
  const Mesh m = unit_cube();
  const Cloud c = mesh_vertices(m);
  EXPECT_EQ(c.points, m.vertices);
  EXPECT_FALSE(c.sensor.has_value());
}

TEST(SampleSurface, DensityBoundsAndUniformity) {
  const Cloud c = sample_surface(unit_square(), 10000.0, 1);
  ASSERT_EQ(c.points.size(), 10000u);
  size_t left = 0, lower_triangle = 0;
  for (const Vec3& p : c.points) {
    EXPECT_TRUE(p.x() >= 0 && p.x() <= 1 && p.y() >= 0 && p.y() <= 1) << p.transpose();
    EXPECT_EQ(p.z(), 0.f);
    left += p.x() < 0.5f;
    lower_triangle += p.y() < p.x();
  }
  EXPECT_NEAR(double(left) / 10000, 0.5, 0.03);
  EXPECT_NEAR(double(lower_triangle) / 10000, 0.5, 0.03);
  EXPECT_EQ(sample_surface(unit_cube(), 100.0, 3).points.size(), 600u);  // area 6
  EXPECT_NEAR(surface_area(unit_cube()), 6.0, 1e-9);
}

TEST(SampleSurface, AreaWeighted) {
  Mesh m;  // a 1 m^2 triangle pair and a 0.02 m^2 triangle far away
  m = unit_square();
  m.vertices.insert(m.vertices.end(), {Vec3(10, 0, 0), Vec3(10.2f, 0, 0), Vec3(10, 0.2f, 0)});
  m.faces.emplace_back(4, 5, 6);
  const Cloud c = sample_surface(m, 20000.0, 5);
  size_t far = 0;
  for (const Vec3& p : c.points) far += p.x() > 5;
  EXPECT_NEAR(double(far) / double(c.points.size()), 0.02 / 1.02, 0.005);
}

TEST(SampleSurface, DeterministicPerSeedAndEmptyCases) {
  const Mesh cube = unit_cube();
  EXPECT_EQ(sample_surface(cube, 500, 42).points, sample_surface(cube, 500, 42).points);
  EXPECT_NE(sample_surface(cube, 500, 42).points, sample_surface(cube, 500, 43).points);
  EXPECT_TRUE(sample_surface(Mesh{}, 500, 1).points.empty());
  EXPECT_TRUE(sample_surface(cube, 0, 1).points.empty());
  EXPECT_TRUE(sample_surface(cube, -5, 1).points.empty());
}

// ---- orientation, size, placement ----

TEST(Up, ParsesAxesAndVectors) {
  EXPECT_EQ(*parse_up("+z"), Vec3(0, 0, 1));
  EXPECT_EQ(*parse_up("-x"), Vec3(-1, 0, 0));
  EXPECT_EQ(*parse_up("y"), Vec3(0, 1, 0));
  EXPECT_EQ(*parse_up(" -Y "), Vec3(0, -1, 0));
  EXPECT_EQ(*parse_up("+X"), Vec3(1, 0, 0));
  EXPECT_EQ(*parse_up("-z"), Vec3(0, 0, -1));
  EXPECT_TRUE(parse_up("-0.762 0.080 -0.642")->isApprox(Vec3(-0.762f, 0.080f, -0.642f).normalized()));
  EXPECT_TRUE(parse_up("0 3 4")->isApprox(Vec3(0, 0.6f, 0.8f)));  // normalised
  for (const char* bad : {"", "+", "w", "+zz", "up", "--z", "0 0 0", "1 2", "1 2 3 4", "nan 0 1", "1 x 2"})
    EXPECT_FALSE(parse_up(bad).ok()) << bad;
  for (int a = 0; a < 3; ++a)
    for (float sign : {1.f, -1.f}) EXPECT_EQ(*parse_up(up_to_string(sign * Vec3::Unit(a))), sign * Vec3::Unit(a));
  EXPECT_EQ(up_to_string(Vec3(0, 0.6f, 0.8f)), "0.000 0.600 0.800");
}

TEST(StandUpright, EachAxisAndATiltedVectorBecomesPlusZByAProperRotation) {
  std::vector<Vec3> ups;
  for (int a = 0; a < 3; ++a) ups.push_back(Vec3::Unit(a)), ups.push_back(-Vec3::Unit(a));
  ups.push_back(Vec3(-0.762f, 0.080f, -0.642f).normalized());
  ups.push_back(Vec3(0.01f, 0, -1).normalized());  // nearly upside down
  for (const Vec3& dir : ups) {
    SCOPED_TRACE(up_to_string(dir));
    const Eigen::Matrix3f r = upright_rotation(dir);
    EXPECT_NEAR(r.determinant(), 1.f, 1e-5f);
    EXPECT_TRUE((r * r.transpose()).isIdentity(1e-5f));
    Mesh m;
    m.vertices = {2.f * dir, Vec3(0, 0, 0)};
    const Mesh up = stand_upright(m, dir);
    EXPECT_TRUE(up.vertices[0].isApprox(Vec3(0, 0, 2), 1e-5f)) << up.vertices[0].transpose();
  }
}

TEST(RandomRotation, ProperDeterministicAndSpreadOverTheSphere) {
  EXPECT_TRUE(random_rotation(7).isApprox(random_rotation(7)));
  EXPECT_FALSE(random_rotation(7).isApprox(random_rotation(8)));
  // Where +z goes: uniform on the sphere, so its mean is near 0 and each hemisphere gets about half.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  int upper = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3f r = random_rotation(uint64_t(i));
    ASSERT_NEAR(r.determinant(), 1.f, 1e-5f);
    const Vec3 z = r * Vec3::UnitZ();
    mean += z.cast<double>();
    upper += z.z() > 0;
  }
  mean /= n;
  EXPECT_LT(mean.norm(), 0.05);  // 3 sigma of the mean of n unit vectors is about 0.03
  EXPECT_NEAR(double(upper) / n, 0.5, 0.03);
}

TEST(RandomTilt, WithinTheCapSpreadOverItAndDeterministic) {
  EXPECT_TRUE(random_tilt(3, 5).isApprox(random_tilt(3, 5)));
  EXPECT_TRUE(random_tilt(3, 0).isIdentity(1e-6f));
  double max_deg = 0, mean_cos = 0;
  int beyond_half = 0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix3f r = random_tilt(uint64_t(i), 5);
    ASSERT_NEAR(r.determinant(), 1.f, 1e-5f);
    const Vec3 up = r * Vec3::UnitZ();
    const double deg = std::acos(std::clamp(double(up.z()), -1.0, 1.0)) * 180 / 3.14159265358979;
    max_deg = std::max(max_deg, deg);
    beyond_half += deg > 2.5 * std::sqrt(2.0);  // half the cap's area lies beyond 5/sqrt(2) degrees
    mean_cos += up.z();
  }
  EXPECT_LE(max_deg, 5.0 + 1e-3);
  EXPECT_GT(max_deg, 4.8);
  EXPECT_NEAR(double(beyond_half) / n, 0.5, 0.04);
  // Turning about a horizontal axis keeps the rotation's own z axis out of the tilt: about z it is fixed.
  const Eigen::Matrix3f r = random_tilt(11, 5);
  const Vec3 axis = Eigen::AngleAxisf(r).axis();
  EXPECT_NEAR(axis.z(), 0.f, 1e-4f);
}

TEST(RotateAboutCentroid, KeepsTheCentroidAndTurnsTheSensor) {
  Cloud c;
  c.points = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(2, 2, 0)};  // centroid (1, 1, 0)
  c.sensor = Vec3(1, 1, 3);
  const Eigen::Matrix3f half_turn_x = Eigen::AngleAxisf(3.14159265f, Vec3::UnitX()).toRotationMatrix();
  const Cloud t = rotate_about_centroid(c, half_turn_x);
  EXPECT_TRUE(t.sensor->isApprox(Vec3(1, 1, -3), 1e-5f));
  EXPECT_TRUE(t.points[0].isApprox(Vec3(0, 2, 0), 1e-5f));
  EXPECT_FALSE(rotate_about_centroid(Cloud{c.points, std::nullopt, {}}, half_turn_x).sensor);
}

TEST(Scale, HeightExtentAndGround) {
  Mesh m;
  m.vertices = {Vec3(1, 2, 3), Vec3(3, 6, 4)};  // extent (2, 4, 1)
  EXPECT_TRUE(scale_uniform(m, 2).vertices[1].isApprox(Vec3(6, 12, 8)));
  EXPECT_NEAR(bounds(scale_to_height(m, 1.8f).vertices).extent().z(), 1.8f, 1e-5f);
  EXPECT_NEAR(bounds(scale_to_largest_extent(m, 0.3f).vertices).extent().maxCoeff(), 0.3f, 1e-6f);
  const Bounds g = bounds(place_on_ground(m).vertices);
  EXPECT_FLOAT_EQ(g.min.z(), 0.f);
  EXPECT_FLOAT_EQ(g.centre().x(), 0.f);
  EXPECT_FLOAT_EQ(g.centre().y(), 0.f);
  Mesh flat;
  flat.vertices = {Vec3(0, 0, 1), Vec3(1, 0, 1)};
  EXPECT_EQ(scale_to_height(flat, 2.f).vertices, flat.vertices);  // zero height: unchanged
}

// ---- hidden point removal ----

TEST(HiddenPointRemoval, SphereKeepsTheFacingCap) {
  const Vec3 centre(1, -2, 0.5f);
  const Points sphere = fibonacci_sphere(4000, 1.0f, centre);
  const Vec3 camera = centre + Vec3(3, 4, 0);  // 5 m from the centre: visible cap up to cos = 0.2
  const Cloud view = hidden_point_removal(sphere, camera);
  ASSERT_TRUE(view.sensor.has_value());
  EXPECT_EQ(*view.sensor, camera);
  const Vec3 to_cam = (camera - centre).normalized();
  size_t front = 0, front_kept = 0;
  for (const Vec3& p : sphere) front += (p - centre).dot(to_cam) > 0.5f;
  for (const Vec3& p : view.points) {
    const float c = (p - centre).dot(to_cam);
    EXPECT_GT(c, -0.02f) << "a point on the back was kept";
    front_kept += c > 0.5f;
  }
  EXPECT_GE(double(front_kept), 0.95 * double(front));  // almost all of the facing cap
  const double fraction = double(view.points.size()) / double(sphere.size());
  EXPECT_GT(fraction, 0.3);  // ideal 0.4: the cap up to cos = 0.2
  EXPECT_LT(fraction, 0.5);
}

TEST(HiddenPointRemoval, CubeShowsOnlyFacingFaces) {
  const Points cube = sample_surface(unit_cube(), 4000, 9).points;
  // Straight on the +x face: only x = 1 points survive.
  const Cloud side = hidden_point_removal(cube, Vec3(4, 0.5f, 0.5f));
  ASSERT_GT(side.points.size(), 200u);
  size_t off_face = 0;
  for (const Vec3& p : side.points) {
    EXPECT_GT(p.x(), 0.95f);  // HPR keeps a thin rim of the grazing side faces, nothing further back
    off_face += p.x() < 0.999f;
  }
  EXPECT_LE(off_face, side.points.size() / 20);
  // From a corner direction three faces show, never a point strictly inside a back face.
  const Cloud corner = hidden_point_removal(cube, Vec3(3, 3, 3));
  size_t back = 0;
  for (const Vec3& p : corner.points)
    back += p.x() < 0.99f && p.y() < 0.99f && p.z() < 0.99f;
  EXPECT_EQ(back, 0u);
  EXPECT_GT(corner.points.size(), cube.size() / 4);
}

TEST(HiddenPointRemoval, DeterministicAndThreadSafe) {
  const Points sphere = fibonacci_sphere(3000, 0.5f, Vec3(0, 0, 0));
  const Vec3 camera(0, 0, 2);
  const std::vector<uint32_t> first = hidden_point_removal_indices(sphere, camera);
  std::vector<std::vector<uint32_t>> results(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] { results[t] = hidden_point_removal_indices(sphere, camera); });
  for (std::thread& t : threads) t.join();
  for (const auto& r : results) EXPECT_EQ(r, first);
  EXPECT_TRUE(std::is_sorted(first.begin(), first.end()));
}

TEST(HiddenPointRemoval, DegenerateInputsAreSilent) {
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  EXPECT_TRUE(hidden_point_removal({}, Vec3(0, 0, 1)).points.empty());
  const Points three = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_EQ(hidden_point_removal(three, Vec3(0, 0, 1)).points.size(), 3u);  // too few to decide
  Points line;  // collinear with the camera: qhull cannot build a 3-D hull without joggling
  for (int i = 1; i <= 20; ++i) line.push_back(Vec3(float(i), 0, 0));
  const std::vector<uint32_t> on_line = hidden_point_removal_indices(line, Vec3(0, 0, 0));
  EXPECT_LE(on_line.size(), line.size());
  Points plane;  // coplanar with the camera
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) plane.push_back(Vec3(float(i), float(j), 0));
  EXPECT_FALSE(hidden_point_removal(plane, Vec3(-5, -5, 0)).points.empty());
  Points with_nan = fibonacci_sphere(200, 1, Vec3(0, 0, 0));
  with_nan.push_back(Vec3(std::nanf(""), 0, 0));
  with_nan.push_back(Vec3(0, 0, 3));  // at the camera
  for (uint32_t i : hidden_point_removal_indices(with_nan, Vec3(0, 0, 3))) EXPECT_LT(i, 200u);
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

// ---- viewpoints and the exploring sequence ----

TEST(PaperViewpoints, SixAroundAtThirtyDegreesAndThreeRadii) {
  const Vec3 centre(1, 2, 3);
  const Points pts = fibonacci_sphere(500, 0.5f, centre);
  const std::vector<Vec3> cams = paper_viewpoints(pts);
  ASSERT_EQ(cams.size(), 6u);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Vec3& p : pts) centroid += p.cast<double>();
  centroid /= double(pts.size());
  double radius = 0;
  for (const Vec3& p : pts) radius = std::max(radius, (p.cast<double>() - centroid).norm());
  for (size_t k = 0; k < cams.size(); ++k) {
    const Eigen::Vector3d d = cams[k].cast<double>() - centroid;
    EXPECT_NEAR(d.norm(), 3 * radius, 1e-4);
    EXPECT_NEAR(d.z() / d.norm(), 0.5, 1e-5);  // sin 30 deg, above the horizon
    const double azimuth = k * kPi / 3;  // 0, 60, ..., 300 deg
    EXPECT_NEAR(d.x() / std::hypot(d.x(), d.y()), std::cos(azimuth), 1e-5);
    EXPECT_NEAR(d.y() / std::hypot(d.x(), d.y()), std::sin(azimuth), 1e-5);
  }
  EXPECT_TRUE(paper_viewpoints({}).empty());
}

TEST(TopDown, OrderIsByDescendingZThenIndex) {
  const Points pts = {Vec3(0, 0, 1), Vec3(0, 0, 3), Vec3(0, 0, std::nanf("")), Vec3(5, 5, 1), Vec3(0, 0, 2)};
  EXPECT_EQ(top_down_order(pts), (std::vector<uint32_t>{1, 4, 0, 3, 2}));
  Cloud c{pts, Vec3(9, 9, 9), {}};
  const Cloud top2 = reveal_top_down(c, 2);
  ASSERT_EQ(top2.points.size(), 2u);
  EXPECT_EQ(top2.points[0].z(), 3.f);
  EXPECT_EQ(top2.points[1].z(), 2.f);
  EXPECT_EQ(*top2.sensor, Vec3(9, 9, 9));
  EXPECT_EQ(reveal_top_down(c, 100).points.size(), 5u);
  EXPECT_TRUE(reveal_top_down(c, 0).points.empty());
  EXPECT_TRUE(top_down_order({}).empty());
}

// highest_points (linear time) keeps exactly the set the sorted order's first `count` hold, ties and
// NaN included.
TEST(TopDown, HighestPointsAreTheSortedOrdersPrefix) {
  std::mt19937 rng(3);
  Points pts;
  for (int i = 0; i < 500; ++i) pts.push_back(Vec3(0, 0, static_cast<float>(rng() % 40)));  // many ties
  pts[17].z() = pts[230].z() = std::nanf("");
  const std::vector<uint32_t> order = top_down_order(pts);
  for (size_t count : {size_t(0), size_t(1), size_t(37), size_t(250), size_t(499), size_t(500), size_t(900)}) {
    std::vector<uint32_t> expected(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(std::min(count, order.size())));
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(highest_points(pts, count), expected) << count;
  }
  EXPECT_TRUE(highest_points({}, 5).empty());
}


// A view of 1000 points on a vertical line, z = 0.000 .. 0.999.
Points column(size_t n = 1000) {
  Points p;
  for (size_t i = 0; i < n; ++i) p.emplace_back(0.f, 0.f, float(i) / float(n));
  return p;
}

TEST(StageCuts, KeypointPrefixHoldsExactlyTheKHighestKeypoints) {
  const Points view = column();
  const std::vector<float> heights = {0.1f, 0.95f, 0.5f, 0.7f, 0.3f};  // unsorted, as extract() gives them
  for (size_t k = 1; k <= heights.size(); ++k) {
    const size_t count = keypoint_prefix(view, heights, k, 0.f);
    const Cloud prefix = reveal_top_down({view, std::nullopt, {}}, count);
    const float lowest = prefix.points.back().z();
    const size_t inside = std::count_if(heights.begin(), heights.end(), [&](float h) { return h >= lowest - 1e-6f; });
    EXPECT_EQ(inside, k) << "k = " << k;
  }
  // The margin lowers the cut by that many metres.
  EXPECT_EQ(keypoint_prefix(view, heights, 1, 0.f), 50u);   // z >= 0.95
  EXPECT_EQ(keypoint_prefix(view, heights, 1, 0.1f), 150u);  // z >= 0.85
}

TEST(StageCuts, KeypointPrefixIsTheWholeViewWithTooFewKeypoints) {
  const Points view = column();
  EXPECT_EQ(keypoint_prefix(view, {0.5f, 0.6f}, 3, 0.f), view.size());
  EXPECT_EQ(keypoint_prefix(view, {}, 1, 0.f), view.size());
  EXPECT_EQ(keypoint_prefix(view, {0.5f}, 0, 0.f), 0u);
  EXPECT_EQ(keypoint_prefix({}, {0.5f}, 1, 0.f), 0u);
}

TEST(StageCuts, FractionPrefixHoldsTheFractionOfTheFullCloud) {
  EXPECT_EQ(fraction_prefix(3000, 10000, 0.10), 1000u);
  EXPECT_EQ(fraction_prefix(3000, 10000, 0.20), 2000u);
  EXPECT_EQ(fraction_prefix(1500, 10000, 0.20), 1500u);  // the view is smaller: all of it
  EXPECT_EQ(fraction_prefix(1500, 0, 0.20), 0u);
  const Points view = column(3000);
  const Cloud prefix = reveal_top_down({view, std::nullopt, {}}, fraction_prefix(view.size(), 10000, 0.1));
  EXPECT_NEAR(double(prefix.points.size()) / 10000.0, 0.10, 1e-9);
}

TEST(StageCuts, ExplorationGrid) {
  EXPECT_EQ(exploration_grid(55, 5), (std::vector<size_t>{1, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55}));
  EXPECT_EQ(exploration_grid(12, 5), (std::vector<size_t>{1, 5, 10, 12}));
  EXPECT_EQ(exploration_grid(55, 1).size(), 55u);
  EXPECT_TRUE(exploration_grid(0, 5).empty());
  EXPECT_EQ(stage_name({StageKind::kKeypoints, 25}), "25kp");
  EXPECT_EQ(stage_name({StageKind::kFraction, 0.1}), "10%");
  EXPECT_EQ(stage_name({StageKind::kFull, 0}), "full");
}
}  // namespace
}  // namespace glimpse
