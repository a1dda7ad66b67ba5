// Harris-3D (sec. 2.2, eq. 2-3) on quadrics away from the coordinate axes, against values worked out by
// hand, and the keypoint options of sec. 2.2 / 3.2.2 (rho1 cap, claim radius, boundary band, response).
//
// Window and units. harris_matrix_eigenvalues(p, sigma) is E = integral of grad f grad f^T G_sigma over
// the quadric z = f(x, y) = 1/2 p1 x^2 + p2 xy + 1/2 p3 y^2 + p4 x + p5 y + p6: A = p4^2 + sigma^2 (p1^2 + p2^2),
// B = p5^2 + sigma^2 (p2^2 + p3^2), C = p4 p5 + sigma^2 (p1 p2 + p2 p3). LocalSurface::lambda_min/max (the
// paper's principal Harris curvatures, eq. 2) are this with the quadric in metres and sigma = sqrt(2) m,
// in 1/m^2: in the point's own frame (p4 = p5 = 0) they are 2 k^2 along each principal direction.
// LocalSurface::harris_response is det - 0.04 tr^2 of E over the fit's own window, sigma = r/2
// (dimensionless): with principal curvatures k1, k2, e_i = (r/2)^2 k_i^2 and R = e1 e2 - 0.04 (e1 + e2)^2.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>

#include "glimpse/features/local_features.h"
#include "glimpse/features/keypoints.h"
#include "glimpse/geometry/neighbourhoods.h"
#include "glimpse/geometry/surface_fit.h"
#include "shapes.h"

namespace glimpse {
namespace {

using test::kPi;

TEST(HarrisMatrix, ClosedFormIsTheGaussianWindowIntegral) {
  // E by quadrature of grad f grad f^T under a normalised Gaussian of sigma, for arbitrary coefficients.
  const double p[5] = {3.0, -1.2, 0.7, 0.15, -0.4};
  for (double sigma : {0.01, 0.05, std::sqrt(2.0)}) {
    double a = 0, b = 0, c = 0, mass = 0;
    const int n = 400;
    const double h = 12 * sigma / n;  // +-6 sigma
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double x = -6 * sigma + (i + 0.5) * h, y = -6 * sigma + (j + 0.5) * h;
        const double g = std::exp(-(x * x + y * y) / (2 * sigma * sigma));
        const double fx = p[0] * x + p[1] * y + p[3], fy = p[1] * x + p[2] * y + p[4];
        a += g * fx * fx, b += g * fy * fy, c += g * fx * fy, mass += g;
      }
    a /= mass, b /= mass, c /= mass;
    const double mean = (a + b) / 2, dev = std::sqrt((a - b) * (a - b) / 4 + c * c);
    const Eigen::Vector2f e = harris_matrix_eigenvalues(p[0], p[1], p[2], p[3], p[4], sigma);
    EXPECT_NEAR(e[0], mean - dev, 1e-4 * (mean + dev)) << "sigma " << sigma;
    EXPECT_NEAR(e[1], mean + dev, 1e-4 * (mean + dev)) << "sigma " << sigma;
  }
  // The paper's eigenvalues are the sqrt(2) m window.
  const Eigen::Vector2f paper = harris_eigenvalues(3.f, -1.2f, 0.7f, 0.15f, -0.4f);
  const Eigen::Vector2f window = harris_matrix_eigenvalues(3.0, -1.2, 0.7, 0.15, -0.4, std::sqrt(2.0));
  EXPECT_FLOAT_EQ(paper[0], window[0]);
  EXPECT_FLOAT_EQ(paper[1], window[1]);
}

// A surface w = f(u, v) of a frame (u, v, w) turned by `pose` and moved to `origin`, sampled on a (u, v)
// grid of `spacing` over |u - u0|, |v - v0| <= half; the sample at (u0, v0) is point 0.
struct PosedSurface {
  Points points;
  Vec3 normal_side;  // a point on the +w side of the surface (the viewpoint)
};
PosedSurface posed_surface(const std::function<float(float, float)>& f, float u0, float v0, float half, float spacing,
                           const Eigen::Matrix3f& pose, const Vec3& origin) {
  PosedSurface s;
  auto place = [&](float u, float v) { return Vec3(origin + pose * Vec3(u, v, f(u, v))); };
  s.points.push_back(place(u0, v0));
  const int n = static_cast<int>(std::round(half / spacing));
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      if (i || j) s.points.push_back(place(u0 + i * spacing, v0 + j * spacing));
  s.normal_side = place(u0, v0) + pose * Vec3(0, 0, 1);
  return s;
}

const Eigen::Matrix3f kOffAxis =
    (Eigen::AngleAxisf(0.7f, Vec3(0.3f, -0.8f, 0.5f).normalized()) * Eigen::AngleAxisf(1.9f, Vec3::UnitZ()))
        .toRotationMatrix();
const Vec3 kSomewhere(1.7f, -0.6f, 2.3f);

LocalSurface surface_at_point0(const PosedSurface& s, float r) {
  const KdTree tree(s.points);
  std::vector<Neighbour> scratch;
  return local_surface(tree, 0, r, s.normal_side, 8, scratch);
}

// e_i = (r/2)^2 k_i^2, R = e1 e2 - 0.04 (e1 + e2)^2.
double expected_response(double k1, double k2, double r) {
  const double e1 = r * r / 4 * k1 * k1, e2 = r * r / 4 * k2 * k2;
  return e1 * e2 - 0.04 * (e1 + e2) * (e1 + e2);
}

TEST(HarrisOffAxis, SaddleHasEqualHarrisCurvaturesAndAPositiveResponse) {
  // w = (u^2 - v^2) / (2a), a = 0.2 m: k1 = +5, k2 = -5 1/m; lambda = 2 k^2 = 50 1/m^2 both (as a
  // sphere: Harris sees gradients, not their signs); rho1 = 2 / sqrt(50) = 0.283 m; r = 2 cm:
  // e = 1e-4 x 25 = 2.5e-3, R = 6.25e-6 - 0.04 x 2.5e-5 = 5.25e-6.
  const float a = 0.2f, r = 0.02f;
  const auto s = posed_surface([&](float u, float v) { return (u * u - v * v) / (2 * a); }, 0, 0, 0.04f, 0.001f,
                               kOffAxis, kSomewhere);
  const LocalSurface q = surface_at_point0(s, r);
  ASSERT_TRUE(q.valid);
  EXPECT_NEAR(q.k1, 5.f, 0.05f);
  EXPECT_NEAR(q.k2, -5.f, 0.05f);
  EXPECT_NEAR(q.lambda_min, 50.f, 0.5f);
  EXPECT_NEAR(q.lambda_max, 50.f, 0.5f);
  EXPECT_NEAR(characteristic_radius(q.lambda_min), 0.2828f, 0.003f);  // eq. 3
  EXPECT_NEAR(q.harris_response, expected_response(5, -5, r), 0.02 * 5.25e-6);
  EXPECT_NEAR(expected_response(5, -5, r), 5.25e-6, 1e-9);
  EXPECT_GT(q.normal.dot(kOffAxis * Vec3::UnitZ()), 0.9999f);
}

TEST(HarrisOffAxis, CylinderHasAFlatDirectionAndANegativeResponse) {
  // Radius R = 0.1 m about an axis along pose * u: k1 = 10 (towards the axis), k2 = 0; lambda = (0, 200)
  // 1/m^2; rho1 infinite (never a keypoint); r = 2.5 cm: e = (0, 1.5625e-4 x 100 = 1.5625e-2),
  // R = -0.04 x 2.441e-4 = -9.77e-6.
  const float R = 0.1f, r = 0.025f;
  // Height above the tangent plane at the lowest line: w = R - sqrt(R^2 - v^2) (valid for |v| < R).
  const auto s = posed_surface([&](float, float v) { return R - std::sqrt(R * R - v * v); }, 0.3f, 0, 0.05f, 0.0015f,
                               kOffAxis, kSomewhere);
  const LocalSurface q = surface_at_point0(s, r);
  ASSERT_TRUE(q.valid);
  EXPECT_NEAR(q.k1, 10.f, 0.3f);
  EXPECT_NEAR(q.k2, 0.f, 0.3f);
  EXPECT_NEAR(q.lambda_max, 200.f, 10.f);
  EXPECT_LT(q.lambda_min, 0.5f);  // 2 x 0.3^2: the k2 tolerance
  EXPECT_NEAR(q.harris_response, expected_response(10, 0, r), 0.06 * 9.77e-6);
  EXPECT_LT(q.harris_response, 0.f);
}

TEST(HarrisOffAxis, TiltedParaboloidAwayFromItsApex) {
  // w = u^2 / (2a) + v^2 / (2b), a = 0.1, b = 0.25, at (u0, v0) = (0.05, 0): f_u = u0/a = 0.5, f_v = 0,
  // E = 1.25, F = 0, G = 1, L = (1/a) / sqrt(1.25), M = 0, N = (1/b) / sqrt(1.25): principal curvatures
  // k_u = L/E = 10 / 1.25^1.5 = 7.155, k_v = N/G = 4 / sqrt(1.25) = 3.578 1/m; lambda = 2 k^2 =
  // (25.60, 102.4) 1/m^2; rho1 = 2 / sqrt(25.60) = 0.3953 m. r = 1.2 cm.
  const float a = 0.1f, b = 0.25f, r = 0.012f;
  const double ku = 10 / std::pow(1.25, 1.5), kv = 4 / std::sqrt(1.25);
  const auto s = posed_surface([&](float u, float v) { return u * u / (2 * a) + v * v / (2 * b); }, 0.05f, 0, 0.025f,
                               0.0006f, kOffAxis, kSomewhere);
  const LocalSurface q = surface_at_point0(s, r);
  ASSERT_TRUE(q.valid);
  EXPECT_NEAR(q.k1, ku, 0.02 * ku);
  EXPECT_NEAR(q.k2, kv, 0.02 * kv);
  EXPECT_NEAR(q.lambda_min, 2 * kv * kv, 0.04 * 2 * kv * kv);
  EXPECT_NEAR(q.lambda_max, 2 * ku * ku, 0.04 * 2 * ku * ku);
  EXPECT_NEAR(characteristic_radius(q.lambda_min), 0.3953f, 0.02f * 0.3953f);
  const double R = expected_response(ku, kv, r);
  EXPECT_NEAR(q.harris_response, R, 0.08 * std::abs(R));
  // The surface normal at that point: (-f_u, -f_v, 1) / sqrt(1.25) in the surface's frame.
  EXPECT_GT(q.normal.dot(kOffAxis * Vec3(-0.5f, 0, 1).normalized()), 0.9995f);
}

// ---- keypoint options -----------------------------------------------------------------------------

FeatureState features_of(const Cloud& c, const KeypointParams& kp, int neighbours = 30) {
  FeatureParams p;
  p.keypoints = kp;
  p.surface.support_neighbours = neighbours;
  auto f = extract(c, p);
  EXPECT_TRUE(f.ok()) << (f.ok() ? "" : f.error().message);
  return f.ok() ? std::move(*f) : FeatureState{};
}

TEST(KeypointOptions, WithoutTheCapABroadSphereHasKeypoints) {
  // A 1 m ball sampled at ~1.3 cm: r ~ 3.7 cm, rho1 = sqrt(2) m > 8 r = 0.3 m: flat for the capped
  // detector, keypoints every rho1 without the cap (the paper's eq. 3 has none).
  const Cloud c{test::sphere(1.f, 60000), std::nullopt, {}};
  KeypointParams capped;
  EXPECT_TRUE(features_of(c, capped).keypoints.empty());
  KeypointParams uncapped;
  uncapped.max_radius_supports = 0;
  const FeatureState f = features_of(c, uncapped);
  ASSERT_FALSE(f.keypoints.empty());
  for (const Keypoint& k : f.keypoints) EXPECT_NEAR(k.characteristic_radius, std::sqrt(2.f), 0.15f);
  EXPECT_EQ(f.diagnostics.keypoints.max_radius_m, 0.f);  // 0: no cap
  // Claims of sqrt(2) m on a sphere of 1 m: the first keypoint's claim reaches 90 deg around it (chord
  // sqrt 2), so at most a handful fit.
  EXPECT_LE(f.keypoints.size(), 6u);
}

TEST(KeypointOptions, ClaimsOfRhoOneAloneLetKeypointsCloserThanR) {
  // Tiny characteristic radii (a crumpled surface): rho1 < r, so max(rho1, r) claims more than rho1.
  Points pts = test::height_field(0.15f, 0.003f, [](float x, float y) {
    return 0.004f * std::sin(x * 300) * std::sin(y * 300);  // bumps ~1 cm apart, curvature ~360 1/m
  });
  const Cloud c{pts, Vec3(0, 0, 1), {}};
  KeypointParams floor_r;  // claim_min_supports = 1
  floor_r.exclude_boundary = false;
  KeypointParams rho_only = floor_r;
  rho_only.claim_min_supports = 0;
  const FeatureState a = features_of(c, floor_r), b = features_of(c, rho_only);
  ASSERT_FALSE(a.keypoints.empty());
  EXPECT_GT(b.keypoints.size(), a.keypoints.size());
  const float r = a.diagnostics.support_radius_m;
  for (size_t i = 0; i < a.keypoints.size(); ++i)
    for (size_t j = i + 1; j < a.keypoints.size(); ++j)
      EXPECT_GT((a.keypoints[i].position - a.keypoints[j].position).norm(), r);
  // rho1 alone still keeps every keypoint out of the others' characteristic spheres.
  for (size_t i = 0; i < b.keypoints.size(); ++i)
    for (size_t j = i + 1; j < b.keypoints.size(); ++j)
      EXPECT_GT((b.keypoints[i].position - b.keypoints[j].position).norm(), b.keypoints[i].characteristic_radius);
}

TEST(KeypointOptions, TheBoundaryBandSetsHowCloseToTheRimKeypointsMayBe) {
  // A hemisphere cap seen from above (its rim a view boundary): a wider band keeps keypoints farther
  // from the rim and finds fewer; band 0 rejects only the boundary points themselves.
  Points cap;
  for (const Vec3& p : test::sphere(0.05f, 6000))
    if (p.z() > 0.01f) cap.push_back(p);
  const Cloud c{cap, Vec3(0, 0, 1), {}};
  size_t previous = SIZE_MAX;
  for (float band : {0.f, 1.f, 2.f}) {
    KeypointParams kp;
    kp.max_radius_supports = 0, kp.claim_min_supports = 0, kp.boundary_band_supports = band;
    const FeatureState f = features_of(c, kp);
    const float r = f.diagnostics.support_radius_m;
    ASSERT_GT(r, 0);
    for (const Keypoint& k : f.keypoints) {
      // The rim circle: z = 0.01, radius sqrt(0.05^2 - 0.01^2); distance from it bounds the band.
      const float rim = std::hypot(k.position.head<2>().norm() - std::sqrt(0.05f * 0.05f - 0.01f * 0.01f),
                                   k.position.z() - 0.01f);
      EXPECT_GT(rim, band * r - 0.2f * r) << "band " << band << ": keypoint within the band";
    }
    EXPECT_LE(f.keypoints.size(), previous) << "band " << band;
    previous = f.keypoints.size();
  }
}

TEST(KeypointOptions, HarrisResponseKeypointsAreLocalMaximaAtTheCubeCorners) {
  const float side = 0.3f;
  const Cloud c{test::cube(side, 0.006f), std::nullopt, {}};
  KeypointParams kp;
  kp.response = KeypointResponse::kHarris;
  const FeatureState f = features_of(c, kp);
  const float r = f.diagnostics.support_radius_m;
  ASSERT_GE(f.keypoints.size(), 8u);
  const KdTree tree(f.cloud.points);
  std::vector<Neighbour> near;
  std::vector<int> per_corner(8, 0);
  for (const Keypoint& k : f.keypoints) {
    const float response = f.surfaces[k.index].harris_response;
    EXPECT_GT(response, 0.f);
    tree.radius(k.position, r, near);
    for (const Neighbour& q : near) {
      if (f.surfaces[q.index].valid) {
        EXPECT_LE(f.surfaces[q.index].harris_response, response);
      }
    }
    int best = 0;
    float best_d = 1e9f;
    for (int i = 0; i < 8; ++i) {
      const Vec3 corner(side * (i & 1), side * ((i >> 1) & 1), side * ((i >> 2) & 1));
      if ((k.position - corner).norm() < best_d) best_d = (k.position - corner).norm(), best = i;
    }
    EXPECT_LT(best_d, 2.5f * r) << "keypoint at " << k.position.transpose() << " is not at a corner";
    ++per_corner[best];
  }
  for (int i = 0; i < 8; ++i) EXPECT_GE(per_corner[i], 1) << "corner " << i << " has no keypoint";
  // Ranked by the response.
  for (size_t i = 1; i < f.keypoints.size(); ++i)
    EXPECT_GE(f.surfaces[f.keypoints[i - 1].index].harris_response, f.surfaces[f.keypoints[i].index].harris_response);
}

}  // namespace
}  // namespace glimpse
