// Local surfaces (sec. 2.2, 3.2.1-3.2.4): per point, the PCA normal over r, the quadric fitted in the
// point's frame, its signed principal curvatures and the Harris-3D eigenvalues of Sipiran & Bustos
// ("principal Harris curvatures", eq. 2). local_surface is the fast fit; reference_local_surface the
// plain textbook one it is tested equal to (its specification).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"
#include "glimpse/geometry/neighbourhoods.h"

namespace glimpse {

struct SurfaceParams {
  float support_radius_m = 0;          // r of sec. 3.2.1; 0 = automatic from the density
  int support_neighbours = 30;         // automatic r: median distance to the this-th nearest neighbour,
                                       // so a neighbourhood holds about this many points, however the
                                       // surface was sampled (grid-like sensors or random samples)
  int min_neighbours = 8;              // fewer neighbours within r: no surface at that point
  int threads = 0;                     // 0 = all cores; results do not depend on it
};

// The radius actually used for a cloud: params.support_radius_m, or the automatic (snapped) one of its
// density (estimate_density).
float support_radius(const NeighbourIndex& tree, const SurfaceParams& params);

// Per point: PCA normal (small window r), the quadric z = 1/2 p1 x^2 + p2 xy + 1/2 p3 y^2 + p4 x +
// p5 y + p6 fitted in the point's PCA frame, its signed principal curvatures and Harris eigenvalues.
struct LocalSurface {
  Vec3 normal = Vec3::Zero();   // unit, oriented (see orient_*); zero when !valid
  float k1 = 0, k2 = 0;         // principal curvatures, k1 >= k2, signed w.r.t. the normal (1/m)
  float lambda_min = 0;         // principal Harris curvatures, lambda_min <= lambda_max (1/m^2)
  float lambda_max = 0;
  // Harris-3D response det(E) - k tr(E)^2 (Sipiran & Bustos, k = kHarrisK) of the Harris matrix E over a
  // Gaussian window of sigma = r/2 (the fit's own weights): dimensionless, > 0 at corner-like points.
  float harris_response = 0;
  uint16_t neighbours = 0;
  bool valid = false;
};

// The Harris matrix of the quadric z = f(x, y) over a Gaussian window of standard deviation sigma,
// E = integral of grad f grad f^T G_sigma, in closed form:
//   A = p4^2 + sigma^2 (p1^2 + p2^2),  B = p5^2 + sigma^2 (p2^2 + p3^2),  C = p4 p5 + sigma^2 (p1 p2 + p2 p3);
// its eigenvalues (min, max). Units: p1..p3 in 1/length, sigma in the same length, E dimensionless.
Eigen::Vector2f harris_matrix_eigenvalues(double p1, double p2, double p3, double p4, double p5, double sigma);

// The paper's principal Harris curvatures (eq. 2): Sipiran & Bustos's closed form A = p4^2 + 2 p1^2 + 2 p2^2
// with the quadric in metres, i.e. harris_matrix_eigenvalues with sigma = sqrt(2) m. On a sphere of radius
// rho both are 2/rho^2 (eq. 2); with the slopes p4, p5 ~ 0 of a fit in the point's own frame they are
// 2 k^2 along each principal direction, so lambda_min ~ 2 min(k1^2, k2^2) (1/m^2).
Eigen::Vector2f harris_eigenvalues(float p1, float p2, float p3, float p4, float p5);

inline constexpr double kHarrisK = 0.04;  // Harris & Stephens' k, as Sipiran & Bustos use it
// det(E) - k tr(E)^2 of the Harris matrix of eigenvalues (l1, l2).
inline double harris_response(double l1, double l2, double k = kHarrisK) { return l1 * l2 - k * (l1 + l2) * (l1 + l2); }

// Signed principal curvatures (k1 >= k2) of z = f(x, y) at the origin from the quadric coefficients.
Eigen::Vector2f principal_curvatures(float p1, float p2, float p3, float p4, float p5);

// One surface per point, all neighbourhoods of radius r. Normals are oriented towards `viewpoint`
// when given, else by propagation (orient_normals_propagated, normal_orientation.h). `cancel` is polled every few hundred
// points; once it returns true the remaining surfaces are left invalid (the caller checks it again).
std::vector<LocalSurface> local_surfaces(const NeighbourIndex& tree, float r,
                                         const std::optional<Vec3>& viewpoint,
                                         const SurfaceParams& params, const CancelFn& cancel = {});

// The surface of one point (the work unit of local_surfaces; also used for incremental updates).
// The normal is oriented towards `viewpoint` when given, else left as PCA gives it.
LocalSurface local_surface(const NeighbourIndex& tree, uint32_t index, float r,
                           const std::optional<Vec3>& viewpoint, int min_neighbours,
                           std::vector<Neighbour>& scratch);

// PCA normal of the neighbourhood of radius `radius` around a point (unoriented); zero if < 3 points.
Vec3 pca_normal(const NeighbourIndex& tree, const Vec3& centre, float radius,
                std::vector<Neighbour>& scratch);


// The textbook fit local_surface must agree with: the r-neighbourhood by brute force, two-pass PCA,
// exact Gaussian weights exp(-2 |d|^2 / r^2), the full weighted design matrix of the quadric solved
// by column-pivoting QR, all in double precision. `neighbours` is 1 when the normal is well defined
// (the two smallest PCA axes do not nearly tie), else 0. Slow: for tests and as the specification.
LocalSurface reference_local_surface(const Points& points, uint32_t index, float r, const Vec3& viewpoint,
                                     int min_neighbours = 8);

}  // namespace glimpse
