#include "glimpse/features/global_descriptors.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <thread>

#include "glimpse/learning/codebook.h"

namespace glimpse {
namespace {

enum class Shape { kSphere, kBox, kCylinder };

// Uniform surface samples of a convex shape centred 1 m in front of a sensor at the origin, keeping
// the points that face the sensor: a single 2.5D view (exact hidden point removal for convex shapes).
Cloud single_view(Shape shape, int samples, uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto u = [&] { return static_cast<float>((rng() >> 40) * 0x1.0p-24); };  // [0, 1)
  auto gauss = [&] { return std::sqrt(-2 * std::log(1 - u())) * std::cos(6.2831853f * u()); };
  const Vec3 centre(0.02f, -0.01f, 1.0f);
  Cloud cloud;
  cloud.sensor = Vec3::Zero();
  for (int i = 0; i < samples; ++i) {
    Vec3 p, n;
    if (shape == Shape::kSphere) {  // radius 0.1 m
      n = Vec3(gauss(), gauss(), gauss()).normalized();
      p = 0.1f * n;
    } else if (shape == Shape::kBox) {  // 0.24 x 0.16 x 0.12 m, faces chosen by area
      const Vec3 half(0.12f, 0.08f, 0.06f);
      const float area[3] = {half.y() * half.z(), half.x() * half.z(), half.x() * half.y()};
      float pick = u() * (area[0] + area[1] + area[2]);
      const int axis = pick < area[0] ? 0 : pick < area[0] + area[1] ? 1 : 2;
      p = Vec3(2 * u() - 1, 2 * u() - 1, 2 * u() - 1).cwiseProduct(half);
      const float sign = u() < 0.5f ? -1.0f : 1.0f;
      p[axis] = sign * half[axis];
      n = Vec3::Zero();
      n[axis] = sign;
    } else {  // cylinder, radius 0.07 m, height 0.22 m, axis along y, caps chosen by area
      const float r = 0.07f, h = 0.22f;
      const float side = 2 * 3.14159265f * r * h, caps = 2 * 3.14159265f * r * r;
      const float phi = 6.2831853f * u();
      if (u() * (side + caps) < side) {
        p = Vec3(r * std::cos(phi), h * (u() - 0.5f), r * std::sin(phi));
        n = Vec3(std::cos(phi), 0, std::sin(phi));
      } else {
        const float rho = r * std::sqrt(u());
        const float sign = u() < 0.5f ? -1.0f : 1.0f;
        p = Vec3(rho * std::cos(phi), sign * h / 2, rho * std::sin(phi));
        n = Vec3(0, sign, 0);
      }
    }
    p += centre;
    if (n.dot(*cloud.sensor - p) > 0) cloud.points.push_back(p);
  }
  return cloud;
}

constexpr std::array<Shape, 3> kShapes = {Shape::kSphere, Shape::kBox, Shape::kCylinder};

bool all_finite(const Eigen::VectorXf& v) { return v.allFinite(); }

// ---- VFH

TEST(Vfh, SizeLayoutAndNormalisation) {
  const Cloud cloud = single_view(Shape::kBox, 6000, 1);
  auto h = vfh(cloud);
  ASSERT_TRUE(h.ok()) << h.error().message;
  ASSERT_EQ(h->size(), kVfhSize);
  EXPECT_TRUE(all_finite(*h));
  EXPECT_GE(h->minCoeff(), 0.0f);
  for (int block = 0; block < 4; ++block)  // f1, f2, f3, size: 45 bins each, ~100 (PCL's normalisation)
    EXPECT_NEAR(h->segment(45 * block, 45).sum(), 100.0f, 1.0f) << "block " << block;
  EXPECT_NEAR(h->tail(128).sum(), 100.0f, 1e-3f);  // viewpoint component

  auto no_size = vfh(cloud, {.fill_size_component = false});
  ASSERT_TRUE(no_size.ok());
  EXPECT_TRUE(no_size->segment(135, 45).isZero(0));
  EXPECT_EQ(no_size->head(135), h->head(135));
}

TEST(Vfh, MatchesPlainPclPipelineOnACleanView) {
  const Cloud cloud = single_view(Shape::kCylinder, 5000, 2);
  auto ours = vfh(cloud, {.normal_radius_m = 0.03f});
  auto theirs = pcl_reference::vfh(cloud, 0.03f);
  ASSERT_TRUE(ours.ok() && theirs.ok());
  EXPECT_LT(l1(*ours, *theirs), 1e-3);  // same normals and VFH: only our validation is added
}

// vfh_with_normals hands PCL a stand-in search tree (VFH never searches): the same signature as PCL's
// own, which builds a tree over the cloud.
TEST(Vfh, WithNormalsMatchesPlainPclOverTheSameNormals) {
  for (Shape shape : kShapes) {
    Cloud cloud = single_view(shape, 4000, 5);
    std::vector<Vec3> normals;
    for (const Vec3& p : cloud.points) normals.push_back((*cloud.sensor - p).normalized());  // facing the sensor
    auto ours = vfh_with_normals(cloud, normals, {});
    auto theirs = pcl_reference::vfh_with_normals(cloud, normals);
    ASSERT_TRUE(ours.ok() && theirs.ok());
    EXPECT_EQ(*ours, *theirs) << "shape " << static_cast<int>(shape);
  }
}

TEST(Vfh, DeterministicForAnyThreadCount) {
  const Cloud cloud = single_view(Shape::kSphere, 8000, 3);
  auto a = vfh(cloud, {.threads = 1});
  auto b = vfh(cloud, {.threads = 1});
  auto c = vfh(cloud, {.threads = 2});
  auto d = vfh(cloud, {.threads = 0});
  ASSERT_TRUE(a.ok() && b.ok() && c.ok() && d.ok());
  EXPECT_EQ(*a, *b);  // bit-identical
  EXPECT_EQ(*a, *c);
  EXPECT_EQ(*a, *d);
}

TEST(Vfh, AutomaticRadiusAndNoSensor) {
  Cloud cloud = single_view(Shape::kBox, 4000, 4);
  auto automatic = vfh(cloud, {.normal_radius_m = 0});
  ASSERT_TRUE(automatic.ok()) << automatic.error().message;
  EXPECT_TRUE(all_finite(*automatic));
  cloud.sensor.reset();
  auto no_sensor = vfh(cloud);
  ASSERT_TRUE(no_sensor.ok()) << no_sensor.error().message;
  EXPECT_TRUE(all_finite(*no_sensor));
  EXPECT_NEAR(no_sensor->tail(128).sum(), 100.0f, 1e-3f);
}

TEST(Vfh, IsolatedPointsAreDroppedNotNaN) {
  Cloud cloud = single_view(Shape::kSphere, 3000, 5);
  cloud.points.push_back(Vec3(1, 1, 3));  // no neighbour within the normal radius: undefined normal
  cloud.points.push_back(Vec3(-1, 1, 3));
  auto h = vfh(cloud);
  ASSERT_TRUE(h.ok()) << h.error().message;
  EXPECT_TRUE(all_finite(*h));
}

TEST(Vfh, InvalidInputIsAnError) {
  Cloud cloud = single_view(Shape::kSphere, 2000, 6);
  Cloud nan = cloud;
  nan.points[10].y() = NAN;
  auto r = vfh(nan);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
  Cloud inf = cloud;
  inf.points[0].x() = INFINITY;
  EXPECT_FALSE(vfh(inf).ok());
  EXPECT_FALSE(vfh(Cloud{}).ok());
  Cloud few;
  few.points.assign(cloud.points.begin(), cloud.points.begin() + 9);
  EXPECT_FALSE(vfh(few).ok());
  Cloud same;
  same.points.assign(50, Vec3(0.1f, 0.2f, 1.0f));
  EXPECT_FALSE(vfh(same).ok());
  // Isolated pairs: even the density's radius (4 x the 1 mm spacing) gives no point 3 neighbours.
  Cloud pairs;
  for (int i = 0; i < 40; ++i) {
    pairs.points.push_back(Vec3(float(i), 0.f, 1.f));
    pairs.points.push_back(Vec3(float(i) + 0.001f, 0.f, 1.f));
  }
  auto no_normals = vfh(pairs, {.normal_radius_m = 0.03f});
  ASSERT_FALSE(no_normals.ok());
  EXPECT_EQ(no_normals.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(no_normals.error().message.find("have a normal"), std::string::npos) << no_normals.error().message;
}

TEST(Vfh, AFixedRadiusTooSmallForTheDensityFallsBackToTheAutomaticOne) {
  const Cloud cloud = single_view(Shape::kSphere, 2000, 6);
  auto tiny_radius = vfh(cloud, {.normal_radius_m = 1e-5f});  // no point has 3 neighbours within it
  ASSERT_TRUE(tiny_radius.ok()) << tiny_radius.error().message;
  auto automatic = vfh(cloud, {.normal_radius_m = 0});
  ASSERT_TRUE(automatic.ok());
  EXPECT_EQ(*tiny_radius, *automatic);
  // A radius that suits the density is used as given.
  auto fixed = vfh(cloud, {.normal_radius_m = 0.03f});
  ASSERT_TRUE(fixed.ok());
  EXPECT_NE(*fixed, *automatic);
}

// ---- ESF

TEST(Esf, SizeNormalisationAndSeedDeterminism) {
  const Cloud cloud = single_view(Shape::kCylinder, 6000, 7);
  auto a = esf(cloud, 11);
  auto b = esf(cloud, 11);
  auto c = esf(cloud, 12);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok()) << a.error().message;
  ASSERT_EQ(a->size(), kEsfSize);
  EXPECT_TRUE(all_finite(*a));
  EXPECT_GE(a->minCoeff(), 0.0f);
  EXPECT_NEAR(a->sum(), 1.0f, 1e-4f);
  EXPECT_EQ(*a, *b);      // same seed: bit-identical
  EXPECT_NE(*a, *c);      // another seed: another sample of triplets...
  EXPECT_LT(l1(*a, *c), 0.25);  // ...of the same distribution
}

TEST(Esf, ThreadSafe) {
  const Cloud cloud = single_view(Shape::kBox, 5000, 8);
  auto serial = esf(cloud, 3);
  ASSERT_TRUE(serial.ok());
  std::array<Expected<Eigen::VectorXf>, 4> results = {internal_error(""), internal_error(""), internal_error(""),
                                                      internal_error("")};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) threads.emplace_back([&, t] { results[t] = esf(cloud, 3); });
  for (std::thread& t : threads) t.join();
  for (const auto& r : results) {
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(*r, *serial);
  }
}

TEST(Esf, StatisticallyCloseToPcl) {
  std::vector<Eigen::VectorXf> ours, theirs;
  for (Shape s : kShapes) {
    const Cloud cloud = single_view(s, 6000, 9);
    auto o = esf(cloud, 1);
    auto t = pcl_reference::esf(cloud);
    ASSERT_TRUE(o.ok() && t.ok());
    ASSERT_EQ(t->size(), kEsfSize);
    ours.push_back(*o);
    theirs.push_back(*t);
  }
  for (size_t i = 0; i < ours.size(); ++i) {
    double other_shapes = INFINITY;
    for (size_t j = 0; j < ours.size(); ++j)
      if (j != i) other_shapes = std::min(other_shapes, l1(ours[i], ours[j]));
    const double to_pcl = l1(ours[i], theirs[i]);
    EXPECT_LT(to_pcl, 0.15) << "shape " << i;  // sampling noise of 20000 triplets (~0.06)
    EXPECT_LT(to_pcl, 0.5 * other_shapes) << "shape " << i;
    // PCL's own output is nearest to ours of the same shape.
    for (size_t j = 0; j < ours.size(); ++j)
      if (j != i) {
        EXPECT_LT(to_pcl, l1(theirs[i], ours[j])) << "shapes " << i << ", " << j;
      }
  }
}

TEST(Esf, InvalidInputIsAnError) {
  Cloud cloud = single_view(Shape::kSphere, 2000, 10);
  cloud.points[3].z() = NAN;
  EXPECT_FALSE(esf(cloud, 1).ok());
  EXPECT_FALSE(esf(Cloud{}, 1).ok());
  Cloud line;  // collinear: no triangle has an area
  for (int i = 0; i < 100; ++i) line.points.push_back(Vec3(0.01f * i, -0.02f * i, 1 + 0.005f * i));
  auto r = esf(line, 1);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
}

// ---- Both separate shapes: other sampling seeds of a shape are nearer (L1, sec. 4) than other shapes.

template <class Descriptor>
void expect_shapes_separate(Descriptor describe) {
  std::vector<Eigen::VectorXf> refs;
  for (Shape s : kShapes) {
    auto h = describe(single_view(s, 5000, 100));
    ASSERT_TRUE(h.ok()) << h.error().message;
    refs.push_back(*h);
  }
  for (size_t truth = 0; truth < kShapes.size(); ++truth)
    for (uint64_t seed : {200, 300}) {
      auto q = describe(single_view(kShapes[truth], 5000, seed));
      ASSERT_TRUE(q.ok());
      double same = l1(*q, refs[truth]), nearest_other = INFINITY;
      for (size_t j = 0; j < refs.size(); ++j)
        if (j != truth) nearest_other = std::min(nearest_other, l1(*q, refs[j]));
      EXPECT_LT(same, nearest_other) << "shape " << truth << " seed " << seed;
    }
}

TEST(Vfh, SeparatesSphereBoxCylinder) {
  expect_shapes_separate([](const Cloud& c) { return vfh(c); });
}

TEST(Esf, SeparatesSphereBoxCylinder) {
  expect_shapes_separate([](const Cloud& c) { return esf(c, 5); });
}

}  // namespace
}  // namespace glimpse
