// Local geometry of a point cloud (sec. 2.2, 3.2.1-3.2.4): cleaning, neighbourhoods, PCA normals and
// their orientation, the local quadric fit with its signed principal curvatures and the Harris-3D
// eigenvalues of Sipiran & Bustos ("principal Harris curvatures", eq. 2), and 2.5D boundary points.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include "glimpse/cloud.h"
#include "glimpse/expected.h"

namespace glimpse {

// The index of the grid cell holding coordinate `v` for cells of size `cell`, clamped to Int's range,
// so huge coordinates or tiny cells share an edge cell (slower, still correct) instead of overflowing.
template <class Int>
Int grid_cell(float v, float cell) {
  const double c = std::floor(static_cast<double>(v) / static_cast<double>(cell));
  constexpr double lo = static_cast<double>(std::numeric_limits<Int>::lowest());
  const double hi = std::ldexp(1.0, std::numeric_limits<Int>::digits) - 1024.0;  // below max, exact
  return c != c ? Int{0} : static_cast<Int>(std::clamp(c, lo, hi));
}

// ---- Cleaning ------------------------------------------------------------------------------------

struct CleanReport {
  size_t input = 0;
  size_t non_finite = 0;   // NaN/Inf coordinates dropped
  size_t duplicates = 0;   // points closer than the tolerance to an earlier kept point
  size_t kept = 0;
};

// Drops NaN/Inf points and duplicates (points in the same cell of a grid of `duplicate_tolerance_m`,
// first one kept; 0 = exact duplicates only). Order of the kept points is preserved.
Cloud clean(const Cloud& cloud, float duplicate_tolerance_m, CleanReport* report = nullptr);

// One point per occupied voxel: the centroid of its points (deterministic; voxels in first-seen order).
Cloud voxel_downsample(const Cloud& cloud, float voxel_m);

// ---- Neighbourhoods ------------------------------------------------------------------------------

struct Neighbour {
  uint32_t index;
  float distance_sq;
};

// Neighbourhood queries over a point set. Every stage that visits neighbourhoods takes this, so a
// static cloud (KdTree) and a growing scan (VoxelIndex) share the same code.
class NeighbourIndex {
 public:
  virtual ~NeighbourIndex() = default;
  // Every point within `radius` of `query` (the query point itself included when it is in the set),
  // in an order that depends only on the point set.
  virtual void radius(const Vec3& query, float radius, std::vector<Neighbour>& out) const = 0;
  // The `k` nearest points, nearest first (ties by index).
  virtual void nearest(const Vec3& query, size_t k, std::vector<Neighbour>& out) const = 0;
  virtual const Points& points() const = 0;
};

// A kd-tree over a fixed point set (nanoflann); the points must outlive the tree and stay unchanged.
class KdTree final : public NeighbourIndex {
 public:
  explicit KdTree(const Points& points);
  ~KdTree() override;
  KdTree(KdTree&&) noexcept;
  KdTree& operator=(KdTree&&) noexcept;

  void radius(const Vec3& query, float radius, std::vector<Neighbour>& out) const override;
  void nearest(const Vec3& query, size_t k, std::vector<Neighbour>& out) const override;
  const Points& points() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A growing point set hashed into cubic cells (append-only): insertion and queries cost what the
// neighbourhood holds, not what the set holds. Radius queries are fastest for radius <= cell size.
class VoxelIndex final : public NeighbourIndex {
 public:
  explicit VoxelIndex(float cell_m);
  uint32_t add(const Vec3& p);  // returns the new point's index
  void radius(const Vec3& query, float radius, std::vector<Neighbour>& out) const override;
  void nearest(const Vec3& query, size_t k, std::vector<Neighbour>& out) const override;
  const Points& points() const override { return points_; }
  float cell() const { return cell_; }

 private:
  struct Key {
    int32_t x, y, z;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const;
  };
  Key key(const Vec3& p) const;
  float cell_;
  Points points_;
  std::unordered_map<Key, std::vector<uint32_t>, KeyHash> cells_;
};

// Median distance from a point to its k-th nearest other point (over a deterministic sample of at
// most `sample` points); 0 for fewer than 2 points. k = 1 gives the median spacing.
float median_knn_distance(const NeighbourIndex& tree, size_t k, size_t sample = 300);

// ---- Local surfaces ------------------------------------------------------------------------------

struct SurfaceParams {
  float support_radius_m = 0;          // r of sec. 3.2.1; 0 = automatic from the density
  int support_neighbours = 30;         // automatic r: median distance to the this-th nearest neighbour,
                                       // so a neighbourhood holds about this many points, however the
                                       // surface was sampled (grid-like sensors or random samples)
  int min_neighbours = 8;              // fewer neighbours within r: no surface at that point
  int threads = 0;                     // 0 = all cores; results do not depend on it
};

// The radius actually used for a cloud: params.support_radius_m, or the automatic one.
float support_radius(const NeighbourIndex& tree, const SurfaceParams& params);

// Per point: PCA normal (small window r), the quadric z = 1/2 p1 x^2 + p2 xy + 1/2 p3 y^2 + p4 x +
// p5 y + p6 fitted in the point's PCA frame, its signed principal curvatures and Harris eigenvalues.
struct LocalSurface {
  Vec3 normal = Vec3::Zero();   // unit, oriented (see orient_*); zero when !valid
  float k1 = 0, k2 = 0;         // principal curvatures, k1 >= k2, signed w.r.t. the normal (1/m)
  float lambda_min = 0;         // principal Harris curvatures, lambda_min <= lambda_max (1/m^2)
  float lambda_max = 0;
  uint16_t neighbours = 0;
  bool valid = false;
};

// Harris-3D matrix of Sipiran & Bustos from the quadric coefficients p1..p5 and its eigenvalues
// (min, max). On a sphere of radius rho both are 2/rho^2 (eq. 2).
Eigen::Vector2f harris_eigenvalues(float p1, float p2, float p3, float p4, float p5);

// Signed principal curvatures (k1 >= k2) of z = f(x, y) at the origin from the quadric coefficients.
Eigen::Vector2f principal_curvatures(float p1, float p2, float p3, float p4, float p5);

// One surface per point, all neighbourhoods of radius r. Normals are oriented towards `viewpoint`
// when given, else by propagation (orient_normals_propagated). `cancel` is polled every few hundred
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

// Normal orientation propagation (Hoppe et al. 1992): a minimum spanning tree over the k-nearest-
// neighbour graph weighted by 1 - |n_i . n_j| flips normals to agree with their parent; each connected
// component is then turned outward (away from its centroid). Deterministic and pose-independent.
void orient_normals_propagated(const NeighbourIndex& tree, std::vector<LocalSurface>& surfaces, int k = 8);

// ---- Boundaries of 2.5D views (sec. 3.2.2) -------------------------------------------------------

// A point is on the boundary when the neighbours projected onto its tangent plane leave an angular
// gap larger than `max_gap_rad` around it (as PCL's BoundaryEstimation).
bool is_boundary_point(const NeighbourIndex& tree, uint32_t index, const Vec3& normal, float r,
                       float max_gap_rad, std::vector<Neighbour>& scratch);

// ---- Hulls ---------------------------------------------------------------------------------------

// Volume of the convex hull of the points (qhull); 0 for fewer than 4 or coplanar points.
double convex_hull_volume(std::span<const Vec3> points);

}  // namespace glimpse
