// Local geometry, keypoints and the 12-D descriptor on analytic shapes (sec. 2.2-2.3, 3.2).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <cmath>
#include <cstring>
#include <random>

#include "glimpse/features/descriptor.h"
#include "glimpse/features/local_features.h"
#include "glimpse/geometry/boundaries.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/normal_orientation.h"
#include "glimpse/geometry/clean.h"
#include "glimpse/geometry/surface_fit.h"
#include "glimpse/features/keypoints.h"
#include "glimpse/features/upright_histogram.h"
#include "shapes.h"

namespace glimpse {
namespace {

using test::kPi;

// Median of a per-point quantity over valid surfaces satisfying `keep`.
template <class Get, class Keep>
float median_over(const std::vector<LocalSurface>& s, const Points& pts, Get get, Keep keep) {
  std::vector<float> v;
  for (size_t i = 0; i < s.size(); ++i)
    if (s[i].valid && keep(pts[i])) v.push_back(get(s[i]));
  EXPECT_FALSE(v.empty());
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(HarrisEigenvalues, SphereQuadricGivesTwoOverRhoSquared) {
  const float rho = 0.2f;  // z = (x^2 + y^2) / (2 rho): p1 = p3 = 1/rho (eq. 2)
  const Eigen::Vector2f l = harris_eigenvalues(1 / rho, 0, 1 / rho, 0, 0);
  EXPECT_NEAR(l[0], 2 / (rho * rho), 1e-3);
  EXPECT_NEAR(l[1], 2 / (rho * rho), 1e-3);
  const Eigen::Vector2f k = principal_curvatures(1 / rho, 0, 1 / rho, 0, 0);
  EXPECT_NEAR(k[0], 1 / rho, 1e-4);
  EXPECT_NEAR(k[1], 1 / rho, 1e-4);
}

TEST(HarrisEigenvalues, CylinderHasOneFlatDirection) {
  const Eigen::Vector2f l = harris_eigenvalues(10, 0, 0, 0, 0);
  EXPECT_NEAR(l[0], 0, 1e-5);
  EXPECT_NEAR(l[1], 200, 1e-3);
}

TEST(LocalSurfaces, SphereCurvatureAndShapeIndex) {
  const float rho = 0.1f;
  const Points pts = test::sphere(rho, 6000);
  const KdTree tree(pts);
  SurfaceParams params;
  const float r = support_radius(tree, params);
  ASSERT_GT(r, 0);
  const auto s = local_surfaces(tree, r, Vec3(0, 0, 1), params);
  auto all = [](const Vec3&) { return true; };
  const float lmin = median_over(s, pts, [](auto& q) { return q.lambda_min; }, all);
  const float lmax = median_over(s, pts, [](auto& q) { return q.lambda_max; }, all);
  EXPECT_NEAR(lmin, 2 / (rho * rho), 0.1 * 2 / (rho * rho));  // eq. 2
  EXPECT_NEAR(lmax, 2 / (rho * rho), 0.1 * 2 / (rho * rho));
  const float shape = median_over(s, pts, [](auto& q) { return modified_shape_index(q.k1, q.k2); }, all);
  EXPECT_NEAR(shape, 0.5f, 0.03f);
  // |k| = 1 / rho at every point; the sign says cap (towards the viewer) or cup (away).
  const float kabs = median_over(s, pts, [](auto& q) { return std::abs(q.k1 + q.k2) / 2; }, all);
  EXPECT_NEAR(kabs, 1 / rho, 0.1 / rho);
}

TEST(LocalSurfaces, CylinderShapeIndexIsOneQuarter) {
  const Points pts = test::cylinder(0.1f, 0.6f, 0.006f);
  const KdTree tree(pts);
  const auto s = local_surfaces(tree, 0.025f, Vec3(1, 0, 0), {});
  auto middle = [](const Vec3& p) { return std::abs(p.z()) < 0.2f; };
  EXPECT_NEAR(median_over(s, pts, [](auto& q) { return modified_shape_index(q.k1, q.k2); }, middle), 0.25f, 0.03f);
  // One principal curvature 1/rho, the other 0: lambda_min ~ 0 (eq. 2 fails: not a keypoint shape).
  EXPECT_LT(median_over(s, pts, [](auto& q) { return q.lambda_min; }, middle), 0.05f * 2 / (0.1f * 0.1f));
}

TEST(LocalSurfaces, SaddleShapeIndexIsZero) {
  const float a = 0.2f;
  const Points pts = test::height_field(0.1f, 0.004f, [&](float x, float y) { return (x * x - y * y) / (2 * a); });
  const KdTree tree(pts);
  const auto s = local_surfaces(tree, 0.02f, Vec3(0, 0, 1), {});
  auto centre = [](const Vec3& p) { return p.head<2>().norm() < 0.02f; };
  EXPECT_NEAR(median_over(s, pts, [](auto& q) { return modified_shape_index(q.k1, q.k2); }, centre), 0.f, 0.05f);
  EXPECT_NEAR(median_over(s, pts, [](auto& q) { return q.k1; }, centre), 1 / a, 0.15 / a);
  EXPECT_NEAR(median_over(s, pts, [](auto& q) { return q.k2; }, centre), -1 / a, 0.15 / a);
}

TEST(LocalSurfaces, PlaneNormalsFaceTheViewpoint) {
  const Points pts = test::jitter(test::plane(0.2f, 0.01f), 0.0005f, 3);
  const KdTree tree(pts);
  for (const Vec3& viewpoint : {Vec3(0.3f, -0.2f, 1.f), Vec3(0.f, 0.5f, -2.f)}) {
    const auto s = local_surfaces(tree, 0.03f, viewpoint, {});
    for (size_t i = 0; i < s.size(); ++i) {
      ASSERT_TRUE(s[i].valid);
      EXPECT_GT(s[i].normal.dot(viewpoint - pts[i]), 0) << "point " << i;
      EXPECT_GT(std::abs(s[i].normal.z()), 0.98f);
    }
  }
}

TEST(LocalSurfaces, PropagationOrientsASphereConsistently) {
  const Points pts = test::sphere(0.15f, 3000, Vec3(1, 2, 3));
  const KdTree tree(pts);
  const auto s = local_surfaces(tree, 0.03f, std::nullopt, {});
  size_t outward = 0, valid = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (!s[i].valid) continue;
    ++valid;
    outward += s[i].normal.dot(pts[i] - Vec3(1, 2, 3)) > 0;
  }
  ASSERT_EQ(valid, pts.size());
  EXPECT_EQ(outward, valid) << "every component is turned outward";
}

TEST(LocalSurfaces, AgreeWithATextbookFit) {
  // A noisy scene of flat faces, edges, corners, a ball and a thin post, seen from one side.
  Points pts = test::jitter(test::cube(0.3f, 0.01f), 0.0008f, 11);
  for (const Vec3& q : test::sphere(0.08f, 3000, Vec3(0.15f, 0.15f, 0.45f))) pts.push_back(q);
  for (const Vec3& q : test::cylinder(0.02f, 0.4f, 0.006f)) pts.push_back(q + Vec3(0.45f, 0.1f, 0.f));
  const Vec3 viewpoint(1.2f, 0.9f, 1.1f);
  const Cloud cloud = clean({pts, viewpoint, {}}, 0, nullptr);
  const KdTree tree(cloud.points);
  const float r = 0.03f;
  const auto fast = local_surfaces(tree, r, viewpoint, {});
  size_t compared = 0;
  for (uint32_t i = 0; i < cloud.points.size(); i += 7) {
    const LocalSurface ref = reference_local_surface(cloud.points, i, r, viewpoint);
    ASSERT_EQ(fast[i].valid, ref.valid) << "point " << i;
    if (!ref.valid || ref.neighbours == 0) continue;
    ++compared;
    EXPECT_GT(fast[i].normal.dot(ref.normal), 1 - 1e-5f) << "point " << i;
    // Curvatures to 0.1 % of their value or of 1/r; Harris eigenvalues likewise in 1/r^2.
    const float k_tol = 1e-3f / r, l_tol = 1e-3f / (r * r);
    EXPECT_NEAR(fast[i].k1, ref.k1, k_tol + 1e-3f * std::abs(ref.k1)) << "point " << i;
    EXPECT_NEAR(fast[i].k2, ref.k2, k_tol + 1e-3f * std::abs(ref.k2)) << "point " << i;
    EXPECT_NEAR(fast[i].lambda_min, ref.lambda_min, l_tol + 1e-3f * ref.lambda_min) << "point " << i;
    EXPECT_NEAR(fast[i].lambda_max, ref.lambda_max, l_tol + 1e-3f * ref.lambda_max) << "point " << i;
    // The response is dimensionless (window r/2) and of the order of (k r)^4 / 16 at most.
    EXPECT_NEAR(fast[i].harris_response, ref.harris_response, 1e-4f + 5e-3f * std::abs(ref.harris_response)) << "point " << i;
  }
  EXPECT_GT(compared, cloud.points.size() / 8) << "most sampled points have a well-defined normal";
}

// The median over a strided sample of each point's distance to its k-th nearest other point, by
// brute force.
float brute_median_knn(const Points& pts, size_t k, size_t sample) {
  const size_t step = std::max<size_t>(1, pts.size() / sample);
  std::vector<float> kth;
  for (size_t i = 0; i < pts.size(); i += step) {
    std::vector<float> d;
    for (const Vec3& q : pts) d.push_back((q - pts[i]).norm());
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
    kth.push_back(d[k]);  // d[0] is the point itself
  }
  std::nth_element(kth.begin(), kth.begin() + static_cast<std::ptrdiff_t>(kth.size() / 2), kth.end());
  return kth[kth.size() / 2];
}

TEST(SupportRadius, MedianKthNeighbourDistanceIsExact) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  // An even surface, and one where the few samples that set the search radius sit in dense blobs
  // while most samples are sparse (the radius then misses most k-th neighbours: the exact fallback).
  Points even = test::jitter(test::cube(0.3f, 0.012f), 0.001f, 2);
  Points uneven(3200);
  for (size_t i = 0; i < uneven.size(); ++i)
    uneven[i] = i % 200 < 40 ? Vec3(0.01f * unit(rng), 0.01f * unit(rng), float(i / 200))
                             : Vec3(unit(rng), unit(rng), unit(rng) * 16);
  for (const Points* pts : {&even, &uneven}) {
    const KdTree tree(*pts);
    for (size_t k : {1, 8, 30}) {
      const float expected = brute_median_knn(*pts, k, 300);
      EXPECT_NEAR(median_knn_distance(tree, k, 300), expected, 1e-5f * expected) << "k = " << k;
    }
  }
}

TEST(Keypoints, PlaneHasNone) {
  Cloud c{test::jitter(test::plane(0.3f, 0.01f), 0.0003f, 7), Vec3(0, 0, 1), {}};
  auto f = extract(c);
  ASSERT_TRUE(f.ok()) << f.error().message;
  EXPECT_TRUE(f->keypoints.empty());
  EXPECT_FALSE(f->diagnostics.note.empty());
}

TEST(Keypoints, CubeKeypointsSitAtTheCornersOnly) {
  const float side = 0.3f;
  Cloud c{test::cube(side, 0.006f), std::nullopt, {}};
  auto f = extract(c);
  ASSERT_TRUE(f.ok()) << f.error().message;
  const float r = f->diagnostics.support_radius_m;
  ASSERT_GE(f->keypoints.size(), 8u);
  std::vector<int> per_corner(8, 0);
  for (const Keypoint& kp : f->keypoints) {
    int best = -1;
    float best_d = 1e9f;
    for (int k = 0; k < 8; ++k) {
      const Vec3 corner(side * (k & 1), side * ((k >> 1) & 1), side * ((k >> 2) & 1));
      const float d = (kp.position - corner).norm();
      if (d < best_d) best_d = d, best = k;
    }
    EXPECT_LT(best_d, 2.5f * r) << "keypoint at " << kp.position.transpose() << " is not at a corner";
    ++per_corner[best];
  }
  for (int k = 0; k < 8; ++k) EXPECT_GE(per_corner[k], 1) << "corner " << k << " has no keypoint";
}

TEST(Keypoints, RadiiGrowMonotonically) {
  Cloud c{test::jitter(test::sphere(0.05f, 2000), 0.0002f, 1), std::nullopt, {}};
  for (const Vec3& p : test::sphere(0.12f, 4000, Vec3(0.3f, 0, 0))) c.points.push_back(p);
  for (const Vec3& p : test::cube(0.2f, 0.008f)) c.points.push_back(p + Vec3(-0.4f, 0, 0));
  auto f = extract(c);
  ASSERT_TRUE(f.ok());
  ASSERT_GE(f->keypoints.size(), 3u);
  for (size_t i = 1; i < f->keypoints.size(); ++i)
    EXPECT_GE(f->keypoints[i].characteristic_radius, f->keypoints[i - 1].characteristic_radius);
  // No keypoint inside another's characteristic sphere (eq. 3 suppression).
  for (size_t i = 0; i < f->keypoints.size(); ++i)
    for (size_t j = i + 1; j < f->keypoints.size(); ++j)
      EXPECT_GT((f->keypoints[i].position - f->keypoints[j].position).norm(),
                std::max(f->keypoints[i].characteristic_radius, f->diagnostics.support_radius_m));
}

TEST(Boundary, GapTestAgreesWithMeasuredAngles) {
  // A point at the origin of a tilted disc of random neighbours with one empty sector: the largest
  // angular gap measured with atan2 must decide exactly as is_boundary_point's arctangent-free test.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  const Vec3 normal = Vec3(0.3f, -0.2f, 1.f).normalized();
  const Vec3 u = normal.unitOrthogonal(), v = normal.cross(u);
  size_t compared = 0, boundaries = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const float gap = unit(rng) * 1.6f * kPi, start = unit(rng) * 2 * kPi;
    const int n = 4 + static_cast<int>(unit(rng) * 40);
    Points pts{Vec3::Zero()};
    std::vector<float> angles;
    for (int i = 0; i < n; ++i) {
      const float t = start + gap + unit(rng) * (2 * kPi - gap), rho = 0.1f + 0.8f * unit(rng);
      pts.push_back(rho * (std::cos(t) * u + std::sin(t) * v));
      angles.push_back(std::atan2(std::sin(t), std::cos(t)));
    }
    if (trial % 3 == 0) pts.push_back(pts[1] * 0.37f), angles.push_back(angles[0]);  // same direction twice
    std::sort(angles.begin(), angles.end());
    float measured = angles.front() + 2 * kPi - angles.back();
    for (size_t i = 1; i < angles.size(); ++i) measured = std::max(measured, angles[i] - angles[i - 1]);
    const KdTree tree(pts);
    std::vector<Neighbour> scratch;
    for (float threshold : {kPi / 4, kPi / 2, 3 * kPi / 4, 1.25f * kPi}) {
      if (std::abs(measured - threshold) < 1e-3f) continue;  // too close to call in single precision
      ++compared;
      const bool expected = measured > threshold;
      boundaries += expected;
      EXPECT_EQ(is_boundary_point(tree, 0, normal, 1.f, threshold, scratch), expected)
          << "trial " << trial << ": gap " << measured << " rad, threshold " << threshold;
    }
  }
  EXPECT_GT(compared, 1500u);
  EXPECT_GT(boundaries, compared / 4) << "both answers are exercised";
  EXPECT_LT(boundaries, 3 * compared / 4);
}

TEST(Keypoints, BoundaryOfAViewGivesNone) {
  // A hemisphere cap seen from above: strongly curved everywhere, but its rim is a view boundary.
  Points cap;
  // (1500 points: the rim's half neighbourhoods fit spuriously high curvatures, 67 of them are
  // candidates the boundary test must turn away.)
  for (const Vec3& p : test::sphere(0.05f, 1500))
    if (p.z() > 0.01f) cap.push_back(p);
  auto with = extract({cap, Vec3(0, 0, 1), {}});
  ASSERT_TRUE(with.ok());
  ASSERT_FALSE(with->keypoints.empty());
  const float r = with->diagnostics.support_radius_m;
  const float rim_z = 0.01f;
  for (const Keypoint& kp : with->keypoints) {
    // Distance from the rim circle, along the surface roughly: vertical gap is a lower bound.
    EXPECT_GT(kp.position.z() - rim_z, 0.5f * r) << "keypoint too close to the rim";
  }
  EXPECT_GT(with->diagnostics.keypoints.boundary_rejected, 0u);
  FeatureParams no_boundary;
  no_boundary.keypoints.exclude_boundary = false;
  auto without = extract({cap, Vec3(0, 0, 1), {}}, no_boundary);
  ASSERT_TRUE(without.ok());
  EXPECT_EQ(without->diagnostics.keypoints.boundary_rejected, 0u);
}

TEST(Descriptor, ShapeIndexEnds) {
  EXPECT_NEAR(modified_shape_index(5, 5), 0.5f, 1e-6);     // cap
  EXPECT_NEAR(modified_shape_index(-5, -5), 0.5f, 1e-6);   // cup
  EXPECT_NEAR(modified_shape_index(5, 0), 0.25f, 1e-6);    // ridge
  EXPECT_NEAR(modified_shape_index(5, -5), 0.f, 1e-6);     // saddle
}

TEST(Descriptor, PfhIsAHistogram) {
  std::vector<Vec3> p = test::sphere(0.1f, 200);
  std::vector<Vec3> n;
  for (const Vec3& q : p) n.push_back(q.normalized());
  const auto h = pfh8(p, n);
  float sum = 0;
  for (float b : h) {
    EXPECT_GE(b, 0);
    sum += b;
  }
  EXPECT_NEAR(sum, 1.f, 1e-5);
  const auto empty = pfh8({}, {});
  for (float b : empty) EXPECT_EQ(b, 0);
}

TEST(Descriptor, PfhChangesLittleWithDensity) {
  // The same ellipsoid-like blob sampled at two densities, same support radius.
  auto blob = [](size_t n) {
    Points p = test::sphere(1.f, n);
    for (Vec3& q : p) q = Vec3(0.15f * q.x(), 0.1f * q.y(), 0.07f * q.z());
    return p;
  };
  FeatureParams params;
  params.surface.support_radius_m = 0.03f;
  const Vec3 probe(0.15f, 0, 0);
  std::array<float, 8> h[2];
  int k = 0;
  for (size_t n : {4000u, 8000u}) {
    const Points pts = blob(n);
    const KdTree tree(pts);
    const auto s = local_surfaces(tree, 0.03f, std::nullopt, params.surface);
    std::vector<Neighbour> nb;
    tree.nearest(probe, 1, nb);
    const uint32_t i = nb[0].index;
    Keypoint kp{i, pts[i], 0.05f, s[i].lambda_min, s[i].lambda_max};
    const Descriptor d = local_descriptor(tree, s, kp, 0.03f, params.descriptor, nb);
    for (int b = 0; b < 8; ++b) h[k][b] = d[b];
    ++k;
  }
  float l1 = 0;
  for (int b = 0; b < 8; ++b) l1 += std::abs(h[0][b] - h[1][b]);
  EXPECT_LT(l1, 0.25f);
}

Cloud transformed(const Cloud& c, const Eigen::Isometry3f& T) {
  Cloud out;
  for (const Vec3& p : c.points) out.points.push_back(T * p);
  if (c.sensor) out.sensor = T * *c.sensor;
  return out;
}

TEST(Descriptor, InvariantToRotationAndTranslation) {
  Cloud c{test::jitter(test::cube(0.25f, 0.006f), 0.0002f, 5), std::nullopt, {}};
  for (const Vec3& p : test::sphere(0.08f, 3000, Vec3(0.5f, 0.1f, 0.1f))) c.points.push_back(p);
  Eigen::Isometry3f T = Eigen::Isometry3f::Identity();
  T.rotate(Eigen::AngleAxisf(0.7f, Vec3(1, 2, 3).normalized()));
  T.translate(Vec3(3, -1, 2));
  auto a = extract(c);
  auto b = extract(transformed(c, T));
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_FALSE(a->keypoints.empty());
  size_t matched = 0;
  for (size_t i = 0; i < a->keypoints.size(); ++i) {
    for (size_t j = 0; j < b->keypoints.size(); ++j) {
      if (a->keypoints[i].index != b->keypoints[j].index) continue;
      ++matched;
      const Descriptor& da = a->descriptors[i];
      const Descriptor& db = b->descriptors[j];
      EXPECT_LT((da.head<8>() - db.head<8>()).lpNorm<1>(), 0.1f);
      EXPECT_NEAR(da[kNormalAngle], db[kNormalAngle], 0.05f);
      EXPECT_NEAR(da[kShapeIndex], db[kShapeIndex], 0.03f);
      EXPECT_NEAR(da[kRho2], db[kRho2], 0.05f * da[kRho2]);
      EXPECT_NEAR(da[kHullVolume], db[kHullVolume], 0.05f * da[kHullVolume] + 1e-9f);
    }
  }
  EXPECT_GE(matched, a->keypoints.size() * 8 / 10);
}

TEST(Extract, DeterministicWhateverTheThreadCount) {
  Cloud c{test::jitter(test::cube(0.3f, 0.005f), 0.0003f, 11), Vec3(1, 1, 1), {}};
  FeatureParams one, two;
  one.surface.threads = 1;
  two.surface.threads = 2;
  auto a = extract(c, one), b = extract(c, two), again = extract(c, two);
  ASSERT_TRUE(a.ok() && b.ok() && again.ok());
  ASSERT_EQ(a->keypoints.size(), b->keypoints.size());
  for (size_t i = 0; i < a->keypoints.size(); ++i) {
    EXPECT_EQ(a->keypoints[i].index, b->keypoints[i].index);
    EXPECT_EQ(a->descriptors[i], b->descriptors[i]);
    EXPECT_EQ(b->descriptors[i], again->descriptors[i]);
  }
}

// A stray point far away makes cells of r too many to hold: extract answers from the kd-tree instead.
// Every other point's neighbourhood is the same, so its surface, keypoints and descriptors must be.
TEST(Extract, AStrayFarPointChangesNoOtherPointsFeatures) {
  Cloud c{test::jitter(test::cube(0.3f, 0.005f), 0.0003f, 11), Vec3(1, 1, 1), {}};
  Cloud stray = c;
  stray.points.push_back(Vec3::Constant(5e3f));
  auto a = extract(c), b = extract(stray);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_GT(a->diagnostics.support_radius_m, 0.f);
  // The stray point neither inflates the density's first guess nor stretches the cells of r: it lies
  // in a border cell, and cells answer both.
  EXPECT_LT(first_guess_cell(stray.points), 1.05f * first_guess_cell(c.points));
  EXPECT_EQ(CellGrid(stray.points, a->diagnostics.support_radius_m).cell(), a->diagnostics.support_radius_m);
  EXPECT_NE(dynamic_cast<const CellGrid*>(first_guess_index(stray.points).get()), nullptr);
  EXPECT_NE(dynamic_cast<const CellGrid*>(fixed_cloud_index(stray.points, a->diagnostics.support_radius_m).get()), nullptr);
  ASSERT_EQ(a->diagnostics.support_radius_m, b->diagnostics.support_radius_m);
  for (size_t i = 0; i < a->surfaces.size(); ++i) {
    ASSERT_EQ(a->surfaces[i].normal, b->surfaces[i].normal) << i;
    ASSERT_EQ(a->surfaces[i].k1, b->surfaces[i].k1) << i;
  }
  ASSERT_EQ(a->keypoints.size(), b->keypoints.size());
  ASSERT_FALSE(a->keypoints.empty());
  for (size_t i = 0; i < a->keypoints.size(); ++i) {
    EXPECT_EQ(a->keypoints[i].index, b->keypoints[i].index);
    EXPECT_EQ(a->descriptors[i], b->descriptors[i]);
  }
}

TEST(Extract, BadInput) {
  auto empty = extract({});
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.error().code, ErrorCode::kInvalidArgument);

  auto few = extract({{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, std::nullopt, {}});
  ASSERT_FALSE(few.ok());
  EXPECT_NE(few.error().message.find("at least"), std::string::npos);

  Cloud nans;
  for (int i = 0; i < 100; ++i) nans.points.emplace_back(NAN, 0.f, static_cast<float>(i));
  auto all_nan = extract(nans);
  ASSERT_FALSE(all_nan.ok());
  EXPECT_NE(all_nan.error().message.find("NaN"), std::string::npos);

  Cloud line;
  for (int i = 0; i < 500; ++i) line.points.emplace_back(0.001f * i, 0.f, 0.f);
  auto collinear = extract(line);
  ASSERT_TRUE(collinear.ok()) << collinear.error().message;
  EXPECT_TRUE(collinear->keypoints.empty());
  EXPECT_EQ(collinear->diagnostics.valid_surfaces, 0u);  // points on a line determine no surface
  EXPECT_NE(collinear->diagnostics.note.find("collinear"), std::string::npos);
  // A slanted line too (float rounding puts its points a hair off the line).
  Cloud slanted;
  for (int i = 0; i < 500; ++i) slanted.points.emplace_back(0.001f * i, 0.002f * i, 0.003f * i);
  auto s = extract(slanted);
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->diagnostics.valid_surfaces, 0u);
  // A thin rod 1 mm across, sampled densely, still is a surface.
  Cloud rod;
  for (int i = 0; i < 2000; ++i)
    rod.points.emplace_back(0.0005f * std::cos(0.7f * i), 0.0005f * std::sin(0.7f * i), 0.0001f * i);
  auto thin = extract(rod);
  ASSERT_TRUE(thin.ok());
  EXPECT_GT(thin->diagnostics.valid_surfaces, 1000u);

  Cloud mixed{test::cube(0.2f, 0.01f), std::nullopt, {}};
  const size_t finite = mixed.points.size();
  mixed.points.emplace_back(INFINITY, 0.f, 0.f);
  mixed.points.push_back(mixed.points.front());
  auto m = extract(mixed);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->diagnostics.clean.non_finite, 1u);
  EXPECT_GE(m->diagnostics.clean.duplicates, 1u);
  EXPECT_LE(m->cloud.points.size(), finite);
}

TEST(Extract, RefusesCoordinatesBeyondAScan) {
  Cloud far{test::cube(0.2f, 0.01f), std::nullopt, {}};
  far.points[5].x() = 3e7f;  // 30,000 km: grid keys of the cleaning stage would overflow
  auto r = extract(far);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(r.error().message.find("point 5"), std::string::npos) << r.error().message;
}

TEST(Extract, StopsWhenCancelled) {
  const Cloud cube{test::cube(0.2f, 0.005f), std::nullopt, {}};
  int polls = 0;
  auto r = extract(cube, {}, [&] { return ++polls > 3; });
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kCancelled);
  EXPECT_TRUE(extract(cube, {}, [] { return false; }).ok());
}

TEST(GridCell, ClampsInsteadOfOverflowing) {
  EXPECT_EQ(grid_cell<int32_t>(2.5f, 1.f), 2);
  EXPECT_EQ(grid_cell<int32_t>(-0.5f, 1.f), -1);
  EXPECT_EQ(grid_cell<int32_t>(1e30f, 1e-9f), grid_cell<int32_t>(3e38f, 1e-9f));
  EXPECT_GT(grid_cell<int32_t>(1e30f, 1e-9f), 2'000'000'000);
  EXPECT_LT(grid_cell<int64_t>(-3e38f, 1e-6f), -4'000'000'000'000'000'000LL);
  EXPECT_EQ(grid_cell<int32_t>(NAN, 1.f), 0);
}

// The three indexes answer every query with the same neighbours, distances and order, to the bit:
// sums over a neighbourhood must not depend on which index found it.
TEST(Neighbourhoods, CellGridFindsWhatTheTreeAndTheVoxelHashFind) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  Points pts;
  for (int i = 0; i < 3000; ++i) pts.push_back(Vec3(u(rng), 0.02f * u(rng), u(rng)));  // a noisy slab
  for (int i = 0; i < 20; ++i) pts.push_back(pts[size_t(i) * 7]);                   // duplicates
  pts.push_back(Vec3(40.f, -3.f, 7.f));  // a stray point far away
  const float cell = 0.03f;
  const KdTree tree(pts);
  const CellGrid grid(pts, cell);
  VoxelIndex voxels(cell);
  for (const Vec3& p : pts) voxels.add(p);
  std::vector<Vec3> queries = {Vec3(40.f, -3.f, 7.f), Vec3(0.6f, 0.f, 0.f), Vec3(-9.f, 2.f, 1.f), Vec3(20.f, -1.f, 3.f)};
  for (int i = 0; i < 300; ++i) queries.push_back(pts[size_t(i) * 10]);
  for (int i = 0; i < 100; ++i) queries.push_back(Vec3(u(rng), u(rng), u(rng)));
  auto same = [](const std::vector<Neighbour>& a, const std::vector<Neighbour>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
      if (a[i].index != b[i].index || std::memcmp(&a[i].distance_sq, &b[i].distance_sq, sizeof(float)) != 0) return false;
    return true;
  };
  std::vector<Neighbour> a, b, c;
  size_t found = 0;
  for (size_t qi = 0; qi < queries.size(); ++qi) {
    const Vec3& q = queries[qi];
    const bool all = qi < 8;  // queries holding every point: a few (each sorts the whole set)
    for (float radius : {0.f, 0.3f * cell, cell, 2.5f * cell, 0.4f, 50.f}) {
      if (radius > 1 && !all) continue;
      tree.radius(q, radius, a);
      grid.radius(q, radius, b);
      voxels.radius(q, radius, c);
      // (nanoflann finds nothing within 0, not even the point itself)
      if (radius > 0) ASSERT_TRUE(same(a, b)) << "radius " << radius << " at " << q.transpose();
      ASSERT_TRUE(same(c, b)) << "radius " << radius << " at " << q.transpose();
      grid.radius_any_order(q, radius, c);
      std::sort(c.begin(), c.end(), [](const Neighbour& x, const Neighbour& y) { return x.index < y.index; });
      ASSERT_TRUE(same(c, b)) << "any order, radius " << radius << " at " << q.transpose();
      found += b.size();
    }
    for (size_t k : {size_t(1), size_t(12), pts.size(), pts.size() + 3}) {
      if (k > 12 && !all) continue;
      tree.nearest(q, k, a);
      grid.nearest(q, k, b);
      ASSERT_TRUE(same(a, b)) << "k " << k << " at " << q.transpose();
    }
  }
  EXPECT_GT(found, 8 * pts.size());  // the 50 m queries alone find every point
  grid.radius(Vec3(NAN, 0.f, 0.f), 1.f, b);
  EXPECT_TRUE(b.empty());
  const Points none;
  const CellGrid empty(none, cell);
  empty.radius(Vec3::Zero(), 1.f, b);
  empty.nearest(Vec3::Zero(), 3, c);
  EXPECT_TRUE(b.empty() && c.empty());
}

// Two dense clusters a kilometre apart (half the points each): cells of a few millimetres spanning both
// would not fit, so the grid's cells grow and fixed_cloud_index answers from the kd-tree instead. The
// grown cells still answer as the tree does.
TEST(Neighbourhoods, FixedCloudIndexTakesTheTreeWhereCellsWouldNotFit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.f, 0.2f);
  Points pts;
  for (int i = 0; i < 4000; ++i) pts.push_back(Vec3(u(rng) + (i % 2 ? 1000.f : 0.f), u(rng), u(rng)));
  const float radius = 0.005f;
  const CellGrid grid(pts, radius);
  EXPECT_GT(grid.cell(), 2 * radius);
  EXPECT_NE(dynamic_cast<const KdTree*>(fixed_cloud_index(pts, radius).get()), nullptr);
  const KdTree tree(pts);
  std::vector<Neighbour> a, b;
  size_t found = 0;
  for (size_t i = 0; i < pts.size(); i += 37) {
    for (float r : {radius, 10 * radius}) {
      tree.radius(pts[i], r, a);
      grid.radius(pts[i], r, b);
      ASSERT_EQ(a.size(), b.size()) << i;
      for (size_t j = 0; j < a.size(); ++j) ASSERT_EQ(a[j].index, b[j].index) << i;
      found += b.size();
    }
    tree.nearest(pts[i], 12, a);
    grid.nearest(pts[i], 12, b);
    ASSERT_EQ(a.size(), 12u);
    for (size_t j = 0; j < a.size(); ++j) ASSERT_EQ(a[j].index, b[j].index) << i;
  }
  EXPECT_GT(found, 300u);
}

TEST(Clean, AChunkedScanKeepsWhatItsWholeCloudKeeps) {
  // Points on a coarse lattice, each sent two or three times in a shuffled order, some nearly equal.
  std::mt19937 rng(4);
  Points all;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 p(float(rng() % 40) * 0.01f, float(rng() % 40) * 0.01f, float(rng() % 5) * 0.01f);
    all.push_back(p);
    if (i % 3 == 0) all.push_back(p + Vec3(0.0004f, 0, 0));  // within a 1 mm tolerance cell, or not
  }
  for (float tolerance : {0.f, 0.001f, 0.005f}) {
    SCOPED_TRACE(tolerance);
    CleanReport report;
    const Cloud whole = clean({all, std::nullopt, {}}, tolerance, &report);
    EXPECT_EQ(report.kept + report.duplicates, all.size());
    EXPECT_GT(report.duplicates, 0u);
    DuplicateFilter filter(tolerance);  // fed in chunks of 7, growing its table as it goes
    Points kept;
    for (size_t begin = 0; begin < all.size(); begin += 7)
      for (size_t i = begin; i < std::min(all.size(), begin + 7); ++i)
        if (filter.keep(all[i])) kept.push_back(all[i]);
    EXPECT_EQ(kept, whole.points);
  }
}

TEST(Clean, WithoutToleranceEveryCopyOfAKeptPointGoes) {
  // Two distinct points closer than any grid's cell, the second sent three times, and -0 as 0.
  const float a = 0.5f, b = std::nextafter(0.5f, 1.f);
  CleanReport report;
  const Cloud kept = clean({{Vec3(a, 0, 0), Vec3(b, 0, 0), Vec3(b, 0, 0), Vec3(b, 0, 0), Vec3(0, -0.f, 0), Vec3(0, 0, 0)},
                            std::nullopt, {}},
                           0.f, &report);
  EXPECT_EQ(kept.points, (Points{Vec3(a, 0, 0), Vec3(b, 0, 0), Vec3(0, -0.f, 0)}));
  EXPECT_EQ(report.duplicates, 3u);
}

TEST(Hull, VolumeOfACubeAndAFlatSet) {
  const Points cube = test::cube(0.5f, 0.05f);
  EXPECT_NEAR(convex_hull_volume(cube), 0.125, 1e-4);
  EXPECT_EQ(convex_hull_volume(test::plane(0.1f, 0.01f)), 0.0);
  EXPECT_EQ(convex_hull_volume(std::vector<Vec3>{}), 0.0);
}

// ---- the size-only baseline ----

TEST(VisibleSize, HeightAndHorizontalExtentsWhateverTheTurnAboutUp) {
  // A 0.8 x 0.3 x 1.7 m box of samples: height 1.7, extents 0.8 and 0.3, also turned 37 degrees.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  Points box;
  for (int i = 0; i < 4000; ++i) box.emplace_back(0.8f * u(rng), 0.3f * u(rng), 1.7f * u(rng));
  const Eigen::Matrix3f turn = Eigen::AngleAxisf(0.65f, Vec3::UnitZ()).toRotationMatrix();
  Points turned;
  for (const Vec3& p : box) turned.push_back(turn * p + Vec3(5, -2, 0.5f));
  for (const Points* pts : {&box, &turned}) {
    const Eigen::VectorXf s = visible_size(*pts);
    ASSERT_EQ(s.size(), kVisibleSizeSize);
    EXPECT_NEAR(s[0], 1.7f, 0.01f);
    EXPECT_NEAR(s[1], 0.8f, 0.01f);
    EXPECT_NEAR(s[2], 0.3f, 0.01f);
  }
  EXPECT_TRUE(visible_size({}).isZero());
}

TEST(Extract, WithoutKeypointsStopsAfterTheSurfaces) {
  const Cloud cube{test::cube(0.3f, 0.006f), std::nullopt, {}};
  FeatureParams p;
  p.find_keypoints = false;
  auto f = extract(cube, p);
  ASSERT_TRUE(f.ok()) << f.error().message;
  EXPECT_TRUE(f->keypoints.empty());
  EXPECT_FALSE(f->surfaces.empty());
  auto with = extract(cube);
  ASSERT_TRUE(with.ok());
  EXPECT_FALSE(with->keypoints.empty());
  EXPECT_EQ(with->surfaces.size(), f->surfaces.size());
}

}  // namespace
}  // namespace glimpse
